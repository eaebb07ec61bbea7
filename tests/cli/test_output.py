"""What htn prints and writes: JSON Lines, output files that are replaced only
by a complete result, and clean ends on signals and closed pipes (issue 10)."""

from __future__ import annotations

import json
import os
import signal
import time

import pytest

from conftest import ROOT, run_htn, start_htn, wait_until

# (m) has one plan per length: an endless stream of plans
ENDLESS = """(defdomain d ((:operator (!a) () () ())
  (:method (m) () ((!a))) (:method (m) () ((!a) (m)))))"""
# (count n) decomposes n levels deep: a task tree as deep as the plan is long
COUNT = """(defdomain d ((:operator (!tick ?n) () () ())
  (:method (count ?n) ((call > ?n 0) (assign ?m (call - ?n 1))) ((!tick ?n) (count ?m))
                      () ())))"""
# a user function that never returns in time; it leaves slow.py.called when it starts
SLOW = (
    "import time\ndef slow(x):\n    open(__file__ + '.called', 'w').close()\n"
    "    time.sleep(30)\n    return 1\n"
)


def files(tmp_path, domain=ENDLESS, problem="(defproblem p d () ((m)))"):
    d, p = tmp_path / "d.jshop", tmp_path / "p.jshop"
    d.write_text(domain)
    p.write_text(problem)
    return d, p


def temporaries(folder) -> list:
    return [f.name for f in folder.iterdir() if f.name.startswith(".htn-")]


# ------------------------------------------------------------------ JSON Lines


def test_json_is_one_line_per_plan_then_the_statistics(tmp_path):
    d, p = files(tmp_path)
    r = run_htn("plan", d, p, "-n", "3", "-f", "json")
    assert r.returncode == 0, r.stderr
    records = [json.loads(line) for line in r.stdout.splitlines()]
    assert [x["type"] for x in records] == ["plan", "plan", "plan", "stats"]
    assert [x["steps"] for x in records[:3]] == [["(!a)"], ["(!a)", "(!a)"], ["(!a)"] * 3]
    assert [x["index"] for x in records[:3]] == [0, 1, 2]
    stats = records[-1]
    assert stats["plans_found"] == 3 and stats["shortest_plan"] == 1
    assert stats["domain"] == str(d) and not stats["timed_out"]
    nodes = records[2]["tree"]["nodes"]
    assert [(n["id"], n["parent"], n["task"]) for n in nodes[:4]] == [
        (0, None, "(root)"),
        (1, 0, "(m)"),
        (2, 1, "(!a)"),
        (3, 1, "(m)"),
    ]


def test_a_deep_task_tree_is_flat_json(tmp_path):
    # a 1,500-level tree: nested JSON of it is refused by json.loads and jq
    d, p = files(tmp_path, domain=COUNT, problem="(defproblem p d () ((count 1500)))")
    r = run_htn("plan", d, p, "-f", "json")
    assert r.returncode == 0, r.stderr
    plan = json.loads(r.stdout.splitlines()[0])  # this process's default recursion limit
    nodes = plan["tree"]["nodes"]
    assert plan["length"] == 1500 and len(nodes) == 1 + 1501 + 1500
    parent = {n["id"]: n["parent"] for n in nodes}
    deepest, depth = max(parent), 0
    while parent[deepest] is not None:
        deepest, depth = parent[deepest], depth + 1
    assert depth == 1501


@pytest.mark.slow
def test_all_json_streams_and_keeps_to_the_timeout(tmp_path):
    d, p = files(tmp_path)
    t0 = time.monotonic()
    proc = start_htn("plan", d, p, "--all", "-f", "json", "--timeout", "3")
    first = json.loads(proc.stdout.readline())
    assert first["type"] == "plan" and proc.poll() is None  # printed while still searching
    rest, err = proc.stdout.read(), proc.stderr.read()  # not communicate(): it skips the
    assert proc.wait(timeout=60) == 0, err  # lines readline() buffered
    assert time.monotonic() - t0 < 3 + 10
    lines = rest.splitlines()
    stats = json.loads(lines[-1])
    assert stats["type"] == "stats" and stats["timed_out"]
    assert stats["plans_found"] == len(lines) > 100
    assert all(json.loads(line)["type"] == "plan" for line in lines[:-1])


@pytest.mark.slow
def test_json_lines_stay_whole_when_the_deadline_interrupts_a_write(tmp_path):
    # -u / PYTHONUNBUFFERED=1 (CI has it) leave stdout without a buffered
    # layer: a write into a full pipe that the deadline's timer interrupts
    # part way dropped the rest of the line (a plan cut at 128 KiB)
    d, p = files(tmp_path)
    proc = start_htn(
        "plan",
        d,
        p,
        "--all",
        "-f",
        "json",
        "--timeout",
        "2",
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    chunks = []
    while True:  # a slow reader: the pipe is full most of the time
        chunk = proc.stdout.read(4096)
        if not chunk:
            break
        chunks.append(chunk)
        time.sleep(0.002)
    assert proc.wait(timeout=60) == 0, proc.stderr.read()
    lines = "".join(chunks).splitlines()
    records = [json.loads(line) for line in lines]  # every line whole
    assert records[-1]["type"] == "stats" and records[-1]["plans_found"] == len(lines) - 1
    assert max(len(line) for line in lines) > 8 * 4096  # lines of many reads each


# ------------------------------------------------------------------ -o and --dot


def test_no_plan_keeps_the_earlier_files(tmp_path):
    d, p = files(
        tmp_path, domain="(defdomain d ((:operator (!a) ((never)) () ()) (:method (m) () ((!a)))))"
    )
    out, dot = tmp_path / "plan.txt", tmp_path / "tree.dot"
    out.write_text("previous plan\n")
    dot.write_text("previous tree\n")
    r = run_htn("plan", d, p, "-o", out, "--dot", dot)
    assert r.returncode == 1
    assert f"{out}: not written (no plan)" in r.stderr
    assert out.read_text() == "previous plan\n" and dot.read_text() == "previous tree\n"
    assert temporaries(tmp_path) == []


def test_dot_streams_one_digraph_per_plan(tmp_path):
    d, p = files(tmp_path)
    dot = tmp_path / "tree.dot"
    assert run_htn("plan", d, p, "-n", "3", "--dot", dot).returncode == 0
    text = dot.read_text()
    assert [line for line in text.splitlines() if line.startswith("digraph")] == [
        "digraph plan_1 {",
        "digraph plan_2 {",
        "digraph plan_3 {",
    ]
    assert run_htn("plan", d, p, "--dot", dot).returncode == 0
    assert dot.read_text().startswith("digraph task_tree {")


def test_ctrl_c_before_the_first_plan_keeps_the_earlier_file(tmp_path):
    d, p = files(
        tmp_path,
        domain="(defdomain d ((:operator (!a) ((call slow 1)) () ()) (:method (m) () ((!a)))))",
    )
    (tmp_path / "slow.py").write_text(SLOW)
    out = tmp_path / "plan.txt"
    out.write_text("previous plan\n")
    proc = start_htn("plan", d, p, "--functions", tmp_path / "slow.py", "-o", out)
    wait_until((tmp_path / "slow.py.called").exists, "the search in the user function", proc)
    assert len(temporaries(tmp_path)) == 1  # -o is open, no plan yet
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err, err
    assert "interrupted; 0 plan(s) found" in err
    assert out.read_text() == "previous plan\n" and temporaries(tmp_path) == []


def test_sigterm_is_handled_like_ctrl_c(tmp_path):
    d, p = files(tmp_path)
    out = tmp_path / "plans.txt"
    proc = start_htn("plan", d, p, "--all", "-f", "jshop", "-o", out)
    proc.stdout.readline()
    time.sleep(0.5)
    proc.send_signal(signal.SIGTERM)
    stdout, err = proc.stdout.read(), proc.stderr.read()
    assert proc.wait(timeout=60) == 143 and "Traceback" not in err, err
    n = stdout.count("Plan cost:") + 1  # the line read above
    assert f"terminated; {n} plan(s) found" in err
    saved = out.read_text()
    assert saved.count("Plan cost:") == n and saved.endswith("--------------------\n")
    assert temporaries(tmp_path) == []


def test_the_temporary_file_of_a_killed_run_is_removed_by_the_next(tmp_path):
    d, p = files(tmp_path)
    proc = start_htn("plan", d, p, "--all", "-f", "jshop", "-o", tmp_path / "plans.txt")
    proc.stdout.readline()
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    left = temporaries(tmp_path)
    assert len(left) == 1 and left[0].startswith(f".htn-{proc.pid}-")
    r = run_htn("plan", d, p, "-o", tmp_path / "other.txt")
    assert r.returncode == 0 and temporaries(tmp_path) == []


# ------------------------------------------------------------------ closed pipes


def first_line_then_close(*args):
    """Run htn, read one line of its output and close the pipe, as ``| head -1``."""
    proc = start_htn(*args)
    line = proc.stdout.readline()
    proc.stdout.close()
    err = proc.stderr.read()
    return proc.wait(timeout=60), line, err


@pytest.mark.parametrize("fmt", ["jshop", "json", "text"])
def test_plan_piped_into_head_exits_quietly(tmp_path, fmt):
    d, p = files(tmp_path)
    out = tmp_path / "plans.txt"
    code, line, err = first_line_then_close("plan", d, p, "--all", "-f", fmt, "-o", out)
    assert (code, err) == (0, "") and line
    assert out.read_text().endswith("--------------------\n")  # whole plans kept
    assert temporaries(tmp_path) == []


@pytest.mark.slow
def test_every_printing_command_exits_quietly_on_a_closed_pipe(tmp_path):
    # 3,000 one-step plans: validate prints more lines than a pipe holds
    d, p = files(
        tmp_path,
        domain="(defdomain d ((:operator (!a ?x) () () ()) (:method (m) ((p ?x)) ((!a ?x)))))",
        problem="(defproblem p d (" + " ".join(f"(p {i})" for i in range(3000)) + ") ((m)))",
    )
    plans = tmp_path / "plans.txt"
    assert run_htn("plan", d, p, "--all", "-o", plans).returncode == 0
    domestic = ROOT / "domains" / "domestic.jshop"
    kitchen = ROOT / "domains" / "kitchen.jshop"
    for args in (
        ["validate", d, p, plans],
        ["stats", "--repeat", "1"],
        ["stats", domestic, ROOT / "problems" / "bring_object.jshop", "--json"],
        ["transform", kitchen, ROOT / "problems" / "tray_three.jshop"],
        ["examples"],
    ):
        code, line, err = first_line_then_close(*args)
        assert (code, err) == (0, ""), (args, code, err)
        assert line
