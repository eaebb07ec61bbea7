"""Hardening, the cases that need a process of their own (issue 18): a full
disk, signals at any instant of a command, and the watchdog that ends user
code which swallows a stop."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from contextlib import contextmanager

import pytest
from test_output import files  # the endless domain, written beside its problem

from conftest import ROOT, run_htn, run_htn_process, start_htn, wait_until

CALLS = """(defdomain d (
  (:operator (!go ?x) () () ((at ?x)))
  (:method (travel ?x) ((call f ?x)) ((!go ?x)))))"""
# f catches everything htn raises into it (Ctrl-C, SIGTERM, the deadline) and goes on
# (it says it was called from inside its try: a signal that came before would end it)
SWALLOW = (
    "import time\ndef f(x):\n    while True:\n        try:\n"
    "            while True:\n                open(__file__ + '.called', 'w').close()\n"
    "                time.sleep(0.05)\n        except BaseException:\n            pass\n"
)


# ------------------------------------------------------------------ 3. a full disk


@contextmanager
def small_disk(folder, size="64k"):
    """A tmpfs of ``size`` at ``folder`` (root only): a disk that fills up."""
    folder.mkdir()
    if (
        os.geteuid() != 0
        or subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(folder)]
        ).returncode
        != 0
    ):
        pytest.skip("mounting a small tmpfs needs root")
    try:
        yield folder
    finally:
        subprocess.run(["umount", "-l", str(folder)])


def test_a_full_disk_is_one_line_and_keeps_what_was_there(tmp_path):
    d, p = files(tmp_path)
    with small_disk(tmp_path / "disk") as disk:
        for option in ("-o", "--dot"):
            earlier = disk / f"earlier{option}"
            earlier.write_text("an earlier result\n")
            r = run_htn("plan", d, p, "-a", option, earlier, "--timeout", "20")
            assert r.returncode == 2 and "Traceback" not in r.stderr
            assert (
                r.stderr.splitlines()[-1]
                == f"{earlier}: {option}: cannot write: No space left on device"
            )
            assert earlier.read_text() == "an earlier result\n"
            assert sorted(f.name for f in disk.iterdir()) == sorted(
                f.name for f in disk.iterdir() if not f.name.startswith(".htn-")
            )
            earlier.unlink()


def test_a_log_on_a_full_disk_ends_on_a_whole_line_and_its_summary(tmp_path):
    # a 600-step plan: the log's second event (its task tree, 120 kB) does not fit
    d, p = files(
        tmp_path,
        """(defdomain c ((:operator (!tick ?n) () () ())
  (:method (count ?n) ((call > ?n 0) (assign ?m (call - ?n 1))) ((!tick ?n) (count ?m))
                      () ())))""",
        "(defproblem p c () ((count 600)))",
    )
    plan = tmp_path / "plan.txt"
    assert run_htn("plan", d, p, "-o", plan).returncode == 0
    with small_disk(tmp_path / "disk") as disk:
        log = disk / "run.jsonl"
        r = run_htn("run", plan, "--robot", "symbolic", "--log", log, "-q")
        assert r.returncode == 2 and "Traceback" not in r.stderr
        assert r.stderr.splitlines()[-1] == f"{log}: --log: cannot write: No space left on device"
        text = log.read_text()
        assert text.endswith("\n")
        events = [json.loads(line) for line in text.splitlines()]  # every line whole
        assert [e["event"] for e in events] == ["header", "summary"]
        assert events[-1]["result"] == "error" and "No space left" in events[-1]["detail"]


# ------------------------------------------------------------------ 6. the watchdog


@pytest.mark.slow
def test_a_function_that_swallows_the_deadline_is_ended(tmp_path):
    d, p = files(tmp_path, CALLS, "(defproblem p d () ((travel home)))")
    fns = tmp_path / "fns.py"
    fns.write_text(SWALLOW)
    began = time.monotonic()
    r = run_htn_process("plan", d, p, "--functions", fns, "--timeout", "2", timeout=120)
    assert r.returncode == 1 and "Traceback" not in r.stderr, r.stderr
    assert "function f did not stop" in r.stderr and r.stderr.startswith("timed out")
    assert time.monotonic() - began < 2 + 5 + 10  # the grace, and a loaded start-up


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_function_that_swallows_a_signal_is_ended(tmp_path, sig):
    d, p = files(tmp_path, CALLS, "(defproblem p d () ((travel home)))")
    fns = tmp_path / "fns.py"
    fns.write_text(SWALLOW)
    proc = start_htn("plan", d, p, "--functions", fns)
    wait_until((tmp_path / "fns.py.called").exists, "the function", proc)
    proc.send_signal(sig)
    began = time.monotonic()
    try:
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()  # still running: the test fails, the process must not stay
    assert proc.returncode == 128 + sig and "Traceback" not in err, err
    assert "function f did not stop" in err and time.monotonic() - began < 10


# ------------------------------------------------------------------ 5. signals at any instant


def catches(pid: int, sig: int) -> bool:
    """Has process ``pid`` a handler of its own for ``sig`` (Linux: SigCgt)?"""
    try:
        with open(f"/proc/{pid}/status") as fh:
            mask = next(line.split()[1] for line in fh if line.startswith("SigCgt:"))
    except (OSError, StopIteration):
        return False
    return bool(int(mask, 16) >> (sig - 1) & 1)


def ended(proc) -> bool:
    """Has ``proc`` ended (exited, or a zombie not yet waited for)?"""
    if proc.poll() is not None:
        return True
    try:
        with open(f"/proc/{proc.pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] in "ZX"
    except OSError:
        return True


def signal_at(argv, at: float, sig: int, log=None, finished=None) -> tuple:
    """Start ``htn ARGV``, send ``sig`` ``at`` seconds after the start (or
    as soon as htn's first line has installed its handlers, if that is
    later: before it the interpreter itself starts, out of any program's
    reach) and return (exit code, stderr, the log's events or None). A
    command that has ended before that instant gets no signal; it is
    appended to ``finished``, if given, and otherwise the test fails."""
    began = time.monotonic()
    proc = start_htn(*argv)
    while not catches(proc.pid, signal.SIGTERM) and proc.poll() is None:
        time.sleep(0.001)
    time.sleep(max(0.0, at - (time.monotonic() - began)))
    if ended(proc):
        assert finished is not None, (argv, at, proc.communicate(timeout=120))
        finished.append(at)
    else:
        proc.send_signal(sig)
    out, err = proc.communicate(timeout=120)
    events = None
    if log is not None and log.exists():
        events = [json.loads(line) for line in log.read_text().splitlines()]
    return proc.returncode, err, events


def check_stopped(code, err, events, sig, what):
    assert code == 128 + sig, (what, code, err)
    assert "Traceback" not in err and "Exception ignored" not in err, (what, err)
    if events is not None:  # a log, once begun, ends with interrupted and its summary
        assert events[-1]["event"] == "summary", (what, events[-3:])


@pytest.mark.parametrize("at", [0.0, 0.05, 0.15, 0.3])
def test_a_signal_during_start_up_exits_quietly(tmp_path, at):
    d, p = files(tmp_path)
    for sig in (signal.SIGINT, signal.SIGTERM):
        code, err, _ = signal_at(["plan", d, p, "-a", "-o", tmp_path / "o.txt"], at, sig)
        check_stopped(code, err, None, sig, f"htn plan, {at} s")


@contextmanager
def cpu_burners(n=2):
    """``n`` processes that keep the cores busy: a loaded machine."""
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    try:
        yield
    finally:
        for b in burners:
            b.kill()
            b.wait()


@pytest.mark.slow
@pytest.mark.sim
def test_signals_at_40_instants_of_plan_and_run_on_a_loaded_machine(tmp_path):
    d, p = files(tmp_path)
    plan = tmp_path / "plan.txt"
    assert (
        run_htn(
            "plan",
            ROOT / "domains" / "domestic.jshop",
            ROOT / "problems" / "bring_object.jshop",
            "-o",
            plan,
        ).returncode
        == 0
    )
    log = tmp_path / "run.jsonl"
    commands = {
        "htn plan": (["plan", d, p, "-a", "-o", tmp_path / "o.txt"], None),
        "htn run --sim": (["run", plan, "--sim", "--log", log, "-q"], log),
    }
    finished = []
    with cpu_burners(2):
        began = time.monotonic()  # how long the run takes, loaded
        assert run_htn("run", plan, "--sim", "-q").returncode == 0
        lasts = time.monotonic() - began
        for i in range(40):
            at = min(3.0, 0.9 * lasts) * i / 39  # 0 s to 3 s, or to the end of the run
            sig = signal.SIGINT if i % 2 == 0 else signal.SIGTERM
            for name, (argv, path) in commands.items():
                if path is not None and path.exists():
                    path.unlink()
                before = len(finished)
                code, err, events = signal_at(
                    argv, at, sig, path, finished if path is not None else None
                )
                what = f"{name}, {sig.name} at {at:.2f} s"
                if len(finished) > before:  # a run quicker than the first one
                    assert code == 0 and events[-1]["result"] == "verified", (what, code, err)
                else:
                    check_stopped(code, err, events, sig, what)
    assert len(finished) <= 8, finished  # most signals came while the run went on


@pytest.mark.slow
@pytest.mark.sim
def test_a_signal_just_after_the_log_header_still_ends_the_log(tmp_path):
    # main blocked the signals with a thread mask while the header was
    # written: the kernel gave the signal to another thread (PyBullet's,
    # NumPy's), Python raised it in the middle of writing, and half the logs
    # ended on their header
    plan = tmp_path / "plan.txt"
    assert (
        run_htn(
            "plan",
            ROOT / "domains" / "domestic.jshop",
            ROOT / "problems" / "bring_object.jshop",
            "-o",
            plan,
        ).returncode
        == 0
    )
    for i in range(10):
        log = tmp_path / f"run{i}.jsonl"
        sig = signal.SIGINT if i % 2 == 0 else signal.SIGTERM
        proc = start_htn("run", plan, "--sim", "--log", log, "-q")
        while not (log.exists() and log.stat().st_size > 0) and proc.poll() is None:
            pass  # as soon as the header is there
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=120)
        events = [json.loads(line) for line in log.read_text().splitlines()]
        check_stopped(proc.returncode, err, events, sig, f"run {i}, {sig.name}")
        assert events[-2]["event"] == "interrupted", events[-3:]
