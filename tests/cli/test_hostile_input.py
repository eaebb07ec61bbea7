"""Hardening against a hostile or careless user (issue 18): data files never
run code, outputs never destroy what they must not, log headers are checked
field by field, ``--timeout`` is a usage error unless it is a positive
number (or inf) and bounds loading too, any exception of user code is one
line at the user's own line, messages quote terms cut short, HDDL arity
errors are located. (Process-level cases, a full disk, signals and the
watchdog: test_stops_and_streams.py.)"""

from __future__ import annotations

import json
import os
import time

import pytest

from conftest import run_htn, run_htn_process

# (go x) calls the user function mark, which leaves a file beside the
# functions file when that file is imported (so a test sees any import)
DOMAIN = """(defdomain d (
  (:operator (!go ?x) () () ((at ?x)))
  (:method (travel ?x) ((call mark ?x)) ((!go ?x)))))"""
PROBLEM = "(defproblem p d () ((travel home)))"
FUNCTIONS = """import os
open(__file__ + ".imported", "w").close()
def mark(x):
    return 1
"""


@pytest.fixture
def made(tmp_path):
    """A domain, problem, functions file and the plan file made with them
    (``htn plan --functions F -o plan.txt``); the import marker removed."""
    d, p, f = tmp_path / "d.jshop", tmp_path / "p.jshop", tmp_path / "fns.py"
    d.write_text(DOMAIN)
    p.write_text(PROBLEM)
    f.write_text(FUNCTIONS)
    plan = tmp_path / "plan.txt"
    r = run_htn("plan", d, p, "--functions", f, "-o", plan)
    assert r.returncode == 0, r.stderr
    marker = tmp_path / "fns.py.imported"
    marker.unlink()
    return d, p, f, plan, marker


# ------------------------------------------------------------------ 1. data is data


def test_a_plan_file_never_imports_the_functions_file_it_names(made, tmp_path):
    d, p, f, plan, marker = made
    assert "; functions sha256: " in plan.read_text()
    r = run_htn("run", plan, "--robot", "symbolic", "-q")
    assert r.returncode == 2 and not marker.exists()
    first = r.stderr.splitlines()[0]
    assert first.startswith(f"{plan}:") and f"give --functions {f}" in first
    # the same file given by the user: it runs
    assert run_htn("run", plan, "--robot", "symbolic", "-q", "--functions", f).returncode == 0
    # another file (same name, other content) is refused, naming both
    other = tmp_path / "other" / "fns.py"
    other.parent.mkdir()
    other.write_text(FUNCTIONS + "# changed\n")
    r = run_htn("run", plan, "--robot", "symbolic", "-q", "--functions", other)
    assert r.returncode == 2 and not (other.parent / "fns.py.imported").exists()
    assert str(other) in r.stderr and str(f) in r.stderr and "SHA-256" in r.stderr


def test_a_log_never_imports_the_functions_file_it_names(made, tmp_path):
    d, p, f, plan, marker = made
    log = tmp_path / "run.jsonl"
    r = run_htn("run", plan, "--robot", "symbolic", "-q", "--functions", f, "--log", log)
    assert r.returncode == 0, r.stderr
    header = json.loads(log.read_text().splitlines()[0])
    assert header["functions"] == str(f) and len(header["functions_sha256"]) == 64
    marker.unlink()
    r = run_htn("run", "--from-log", log)
    assert r.returncode == 2 and not marker.exists()
    assert r.stderr.startswith(f"{log}:1: ") and f"give --functions {f}" in r.stderr
    again = tmp_path / "again.jsonl"
    r = run_htn("run", "--from-log", log, "--functions", f, "--log", again, "-q")
    assert r.returncode == 0, r.stderr
    f.write_text(FUNCTIONS + "# changed since\n")
    r = run_htn("run", "--from-log", log, "--functions", f)
    assert r.returncode == 2 and "SHA-256" in r.stderr


def test_a_log_whose_domain_changed_is_refused(made, tmp_path):
    d, p, f, plan, marker = made
    log = tmp_path / "run.jsonl"
    assert (
        run_htn("run", plan, "--robot", "symbolic", "-q", "--functions", f, "--log", log).returncode
        == 0
    )
    d.write_text(DOMAIN + "\n; edited\n")
    r = run_htn("run", "--from-log", log, "--functions", f)
    assert r.returncode == 2
    assert r.stderr.startswith(f"{log}:1: the domain file {d} has changed since this run")


# ------------------------------------------------------------------ 4. --from-log headers


@pytest.mark.parametrize(
    "field,value,says",
    [
        ("seed", "x", "expected an integer"),
        ("seed", 1.5, "expected an integer"),
        ("plan_index", 0, "1 or more"),
        ("plan_index", True, "1 or more"),
        ("faults", 3, "faults text"),
        ("retries", {"!go": "many"}, "retry limits"),
        ("retries", [1], "retry limits"),
        ("plan_sha256", 7, "SHA-256"),
        ("replan", "yes", "true or false"),
        ("robot", None, "robot's name"),
        ("plan", ["a"], "expected a path"),
    ],
)
def test_every_header_field_is_checked(made, tmp_path, field, value, says):
    d, p, f, plan, marker = made
    log = tmp_path / "run.jsonl"
    assert (
        run_htn("run", plan, "--robot", "symbolic", "-q", "--functions", f, "--log", log).returncode
        == 0
    )
    lines = log.read_text().splitlines()
    header = json.loads(lines[0])
    header[field] = value
    log.write_text("\n".join([json.dumps(header), *lines[1:]]) + "\n")
    r = run_htn("run", "--from-log", log, "--functions", f)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    first = r.stderr.splitlines()[0]
    assert first.startswith(f'{log}:1: header field "{field}": ') and says in first, first


# ------------------------------------------------------------------ 2. outputs


def test_an_output_that_is_an_input_is_refused_and_left_alone(made, tmp_path):
    d, p, f, plan, marker = made
    before = {x: x.read_bytes() for x in (d, plan)}
    r = run_htn("plan", d, p, "-o", d)
    assert r.returncode == 2 and "is an input of this command" in r.stderr
    link = tmp_path / "alias.jshop"
    link.symlink_to(d)
    r = run_htn("plan", d, p, "--dot", link)
    assert r.returncode == 2 and "is an input of this command" in r.stderr
    r = run_htn("run", plan, "--robot", "symbolic", "--functions", f, "--log", plan)
    assert r.returncode == 2 and "--log: is an input" in r.stderr
    r = run_htn("plan", d, p, "-o", tmp_path / "x.txt", "--dot", tmp_path / "x.txt")
    assert r.returncode == 2 and "is also where" in r.stderr
    assert {x: x.read_bytes() for x in (d, plan)} == before


def test_devices_and_fifos_are_refused_and_links_written_through(made, tmp_path):
    d, p, f, plan, marker = made
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for target, kind in ((fifo, "a FIFO"), ("/dev/null", "a character device")):
        r = run_htn("plan", d, p, "-o", target)
        assert r.returncode == 2 and f"is {kind}, not a file" in r.stderr, r.stderr
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")
    assert not fifo.is_file() and fifo.exists()
    real = tmp_path / "real.txt"
    real.write_text("old\n")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    assert run_htn("plan", d, p, "--functions", f, "-o", link).returncode == 0
    assert link.is_symlink() and "Plan cost:" in real.read_text()


# ------------------------------------------------------------------ 6. --timeout


@pytest.mark.parametrize("value", ["0", "-1", "nan", "NaN", "soon", ""])
def test_a_timeout_that_is_no_positive_number_is_a_usage_error(made, value):
    d, p, f, plan, marker = made
    for args in (("plan", d, p), ("validate", d, p, plan), ("run", plan, "--robot", "symbolic")):
        r = run_htn(*args, "--functions", f, "--timeout", value)
        assert r.returncode == 2 and "Traceback" not in r.stderr
        assert "Invalid value for '--timeout'" in r.stderr, r.stderr


@pytest.mark.parametrize("value", ["inf", "1e300", "Infinity"])
def test_a_huge_timeout_is_no_limit(made, value):
    d, p, f, plan, marker = made
    r = run_htn("plan", d, p, "--functions", f, "--timeout", value)
    assert r.returncode == 0, r.stderr


def test_the_timeout_bounds_loading_a_functions_file(made, tmp_path):
    d, p, f, plan, marker = made
    loops = tmp_path / "loops.py"
    loops.write_text("while True:\n    pass\n")
    for args in (("plan", d, p), ("validate", d, p, plan)):
        began = time.monotonic()
        r = run_htn_process(*args, "--functions", loops, "--timeout", "1", timeout=60)
        assert r.returncode == 1 and "timed out" in r.stderr, r.stderr
        assert "Traceback" not in r.stderr and time.monotonic() - began < 20


# ------------------------------------------------------------------ 7. user code


@pytest.mark.parametrize(
    "raising",
    [
        "raise BaseException('odd')",
        "raise GeneratorExit()",
        "raise KeyboardInterrupt()",
        "raise SystemExit(4)",
        "import sys; sys.exit('bye')",
        "raise MemoryError()",
    ],
)
def test_any_exception_at_import_is_one_line_at_the_users_line(made, tmp_path, raising):
    d, p, f, plan, marker = made
    bad = tmp_path / "bad.py"
    bad.write_text(f"x = 1\n{raising}\n")
    r = run_htn("plan", d, p, "--functions", bad)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.splitlines()[0].startswith(f"{bad}:2: loading failed: "), r.stderr


@pytest.mark.parametrize(
    "body,says",
    [
        ("raise GeneratorExit()", "raised GeneratorExit"),
        ("raise BaseException('odd')", "raised BaseException: odd"),
        ("raise KeyboardInterrupt()", "raised KeyboardInterrupt"),
    ],
)
def test_any_exception_of_a_function_is_one_line_at_the_users_line(made, tmp_path, body, says):
    d, p, f, plan, marker = made
    bad = tmp_path / "bad.py"
    bad.write_text(f"def mark(x):\n    {body}\n")
    r = run_htn("plan", d, p, "--functions", bad)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    first = r.stderr.splitlines()[0]
    assert first.startswith(f"{bad}:2: function mark {says}"), first
    assert f"called at {d}:3:" in first


def test_junk_returned_by_a_function_runs_none_of_its_methods(made, tmp_path):
    d, p, f, plan, marker = made
    bad = tmp_path / "bad.py"
    bad.write_text(
        "class S(str):\n    def lower(self):\n        raise RuntimeError('no')\n"
        "    def __repr__(self):\n        raise RuntimeError('no')\n"
        "class N:\n    def __repr__(self):\n        while True: pass\n"
        "def mark(x):\n    return S('Yes')\ndef junk(x):\n    return N()\n"
    )
    assert run_htn("plan", d, p, "--functions", bad).returncode == 0
    d.write_text(DOMAIN.replace("call mark", "call junk"))
    r = run_htn("plan", d, p, "--functions", bad, timeout=60)
    assert r.returncode == 2 and "returned an object of class N, which is not a term" in r.stderr, (
        r.stderr
    )


# ------------------------------------------------------------------ 8. bounded messages


@pytest.mark.slow
def test_a_huge_term_in_a_message_is_cut_and_quick(tmp_path):
    d, p = tmp_path / "d.jshop", tmp_path / "p.jshop"
    d.write_text("(defdomain d ((:operator (!a ?l) ((big ?l) (call < ?l 1)) () ())))")
    p.write_text("(defproblem p d ((big (" + " ".join(["x"] * 300_000) + "))) ((!a ?l)))")
    began = time.monotonic()
    r = run_htn("plan", d, p)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    first = r.stderr.splitlines()[0]
    assert "call <: expected a number, got (x x x" in first and first.endswith("...")
    assert len(first) < 400 and time.monotonic() - began < 60


# ------------------------------------------------------------------ 9. HDDL arity

HDDL_DOMAIN = """(define (domain d) (:requirements :hierarchy) (:types thing)
  (:predicates (done ?x - thing))
  (:task t :parameters (?x - thing))
  (:method m :parameters (?x ?y - thing) :task (t ?x ?y)
    :ordered-subtasks (and (a ?x)))
  (:action a :parameters (?x - thing) :effect (done ?x)))"""
HDDL_PROBLEM = """(define (problem p) (:domain d) (:objects o - thing)
  (:htn :parameters () :ordered-subtasks (and (t o))) (:init))"""


def test_a_method_task_with_more_arguments_than_its_task_is_located(tmp_path):
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(HDDL_DOMAIN)
    p.write_text(HDDL_PROBLEM)
    r = run_htn("plan", d, p)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.startswith(f"{d}:4:49: t takes 1 argument(s), given 2"), r.stderr


def test_transform_and_examples_refuse_what_they_must_not_write(tmp_path):
    from conftest import ROOT

    d = tmp_path / "kitchen.jshop"
    d.write_bytes((ROOT / "domains" / "kitchen.jshop").read_bytes())
    before = d.read_bytes()
    r = run_htn("transform", d, ROOT / "problems" / "tray_three.jshop", "-o", d)
    assert r.returncode == 2 and f"{d}: -o: is an input of this command" in r.stderr
    assert d.read_bytes() == before
    assert run_htn("examples", tmp_path / "ex").returncode == 0
    victim = tmp_path / "ex" / "domains" / "domestic.jshop"
    victim.unlink()
    os.mkfifo(victim)
    r = run_htn("examples", tmp_path / "ex", "--force", timeout=60)
    assert r.returncode == 2 and "is a FIFO, not a file" in r.stderr and not victim.is_file()
