"""``htn run`` gives every bad input a clean answer before the robot moves, and
every log it writes ends with a summary (through the real command line)."""

from __future__ import annotations

import json
import os
import signal
import time

import pytest

from conftest import ROOT, interrupt_run, run_htn, start_htn, wait_until

DOMAIN = ROOT / "domains" / "domestic.jshop"
BRING = ROOT / "problems" / "bring_object.jshop"


@pytest.fixture(scope="module")
def plan_text(tmp_path_factory):
    plan = tmp_path_factory.mktemp("plan") / "plan.txt"
    assert run_htn("plan", DOMAIN, BRING, "-o", plan).returncode == 0
    return plan.read_text()


@pytest.fixture
def plan(tmp_path, plan_text):
    path = tmp_path / "plan.txt"
    path.write_text(plan_text)
    return path


def one_error_line(r, exit_code=2):
    assert r.returncode == exit_code, r.stdout + r.stderr
    assert "Traceback" not in r.stderr
    return r.stderr.splitlines()[0]


def line_of(path, text):
    return next(n for n, t in enumerate(path.read_text().splitlines(), 1) if text in t)


@pytest.mark.parametrize("robot", ["--sim", "symbolic"])
def test_a_step_with_an_unknown_location_is_found_before_the_robot_moves(plan, tmp_path, robot):
    plan.write_text(
        plan.read_text().replace(
            "(!move_base jenny counter_front sofa_front)",
            "(!move_base jenny counter_front nowhere)",
        )
    )
    log = tmp_path / "run.jsonl"
    log.write_text("an earlier log\n")
    args = ["--sim"] if robot == "--sim" else ["--robot", robot]
    r = run_htn("run", plan, *args, "--log", log)
    n = line_of(plan, "nowhere")
    assert one_error_line(r) == (
        f"{plan}:{n}:1: step 5 cannot run: precondition of (!move_base jenny counter_front "
        "nowhere) does not hold: (location nowhere ?x ?y ?theta) has no satisfier"
    )
    assert r.stdout == ""  # no step was executed
    assert log.read_text() == "an earlier log\n"


@pytest.mark.sim
def test_a_step_with_a_variable_is_an_input_error_at_its_column(plan):
    plan.write_text(plan.read_text().replace("(!say jenny here_you_are)", "(!say jenny ?x)"))
    r = run_htn("run", plan, "--sim")
    n = line_of(plan, "?x")
    assert one_error_line(r) == (
        f"{plan}:{n}:13: (!say jenny ?x) has a variable, ?x: a plan to run must be ground"
    )


def test_retry_limits_of_operators_the_domain_lacks_are_rejected(plan):
    r = run_htn("run", plan, "--robot", "symbolic", "--retries", "grasp=1,bogus=3")
    assert one_error_line(r) == "--retries: the domain domestic has no operator !bogus"


@pytest.mark.sim
def test_output_folders_are_checked_before_work_starts(plan, tmp_path):
    r = run_htn("run", plan, "--sim", "--log", tmp_path / "missing" / "x.jsonl")
    assert one_error_line(r) == (
        f"{tmp_path / 'missing' / 'x.jsonl'}: --log: no such folder {tmp_path / 'missing'}"
    )
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    r = run_htn("run", plan, "--sim", "--snapshots", blocker / "shots")
    assert one_error_line(r) == (
        f"{blocker / 'shots'}: --snapshots: cannot make a folder under {blocker}, which is a file"
    )
    r = run_htn("run", plan, "--sim", "--snapshots", "/proc/htn-shots")  # read-only, even for root
    assert one_error_line(r).startswith("/proc/htn-shots: --snapshots: cannot write in /proc: ")
    r = run_htn("run", plan, "--sim", "--bt-dot", tmp_path / "missing" / "bt.dot")
    assert "--bt-dot: no such folder" in one_error_line(r)
    assert sorted(os.listdir(tmp_path)) == ["a-file", "plan.txt"]  # nothing written


@pytest.mark.sim
def test_gui_without_a_display_says_so(plan):
    env_none = {k: v for k, v in os.environ.items() if k != "DISPLAY"}
    for env, message in (
        (env_none, "--gui needs a display (DISPLAY is not set)"),
        ({**env_none, "DISPLAY": ":93"}, "--gui: no X server answers on DISPLAY=:93"),
    ):
        r = run_htn("run", plan, "--sim", "--gui", env=env, timeout=120)
        assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr


def events(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def catches(pid: int, sig: int) -> bool:
    """Has process ``pid`` a handler of its own for ``sig`` (Linux: SigCgt)?"""
    with open(f"/proc/{pid}/status") as fh:
        mask = next(line.split()[1] for line in fh if line.startswith("SigCgt:"))
    return bool(int(mask, 16) >> (sig - 1) & 1)


@pytest.mark.sim
def test_sigterm_halts_the_tree_like_ctrl_c(plan, tmp_path):
    log = tmp_path / "run.jsonl"
    proc = start_htn("run", plan, "--sim", "--log", log, "-q")
    wait_until(
        lambda: log.exists() and '"event": "verified"' in log.read_text(),
        "a verified action in the log",
        proc,
    )
    out, _, evs = interrupt_run(proc, signal.SIGTERM, log)
    assert "SIGTERM" in evs[-2]["detail"]
    assert out.startswith("interrupted: ")


# (push-it ?x) calls a user function. Once the test arms it (after planning:
# the run executes the plan file's task tree without planning again), its
# next call is repair planning, between two ticks: it leaves a marker and
# takes long.
PUSHING = """(defdomain pushing ((:operator (!push ?x) () () ((pushed ?x)))
  (:method (push-it ?x) ((call slow ?x)) ((!push ?x)))))"""
SLOW_WHEN_ARMED = """import os, time
def slow(x):
    if os.path.exists(__file__ + ".armed"):
        open(__file__ + ".repairing", "w").close()
        time.sleep(30)
    return 1
"""


def test_sigterm_while_repair_plans_between_ticks_is_logged_as_sigterm(tmp_path):
    domain, problem, fns = tmp_path / "d.jshop", tmp_path / "p.jshop", tmp_path / "slow.py"
    domain.write_text(PUSHING)
    problem.write_text("(defproblem one pushing () ((push-it box)))")
    fns.write_text(SLOW_WHEN_ARMED)
    plan, log = tmp_path / "plan.txt", tmp_path / "run.jsonl"
    assert run_htn("plan", domain, problem, "--functions", fns, "-o", plan).returncode == 0
    (tmp_path / "slow.py.armed").touch()
    # the push never has its effect: aborted, retried once (the default for a
    # domain without a .toml) and aborted again; then repair re-plans (push-it box)
    proc = start_htn(
        "run",
        plan,
        "--robot",
        "symbolic",
        "--faults",
        "effect=1",
        "--replan",
        "--functions",
        fns,
        "--log",
        log,
        "-q",
    )
    wait_until((tmp_path / "slow.py.repairing").exists, "repair planning", proc)
    out, err, evs = interrupt_run(proc, signal.SIGTERM, log)
    assert [e["event"] for e in evs if e["event"] in ("aborted", "replanned")] == ["aborted"] * 2
    assert evs[-2]["detail"] == "stopped by SIGTERM; the robot holds its pose"
    assert out.startswith("interrupted: 0 of 1 steps verified") and err == "terminated\n"


# counted from the moment htn's entry point has its handlers (before that,
# the interpreter itself is starting up and a Ctrl-C is Python's to report)
@pytest.mark.sim
@pytest.mark.parametrize("delay", [0.0, 0.1, 0.3, 0.7])
def test_ctrl_c_during_start_up_exits_130_without_a_traceback(plan, tmp_path, delay):
    log = tmp_path / "run.jsonl"
    proc = start_htn("run", plan, "--sim", "--log", log, "-q")
    wait_until(lambda: catches(proc.pid, signal.SIGTERM), "htn's signal handlers", proc)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, out + err
    assert "Traceback" not in err and "Exception ignored" not in err
    if log.exists():  # a log, once begun, ends with its summary
        evs = events(log)
        assert evs[0]["event"] == "header" and evs[-1]["event"] == "summary"
