"""``--explain``: why there is no plan, at the deepest dead end of the search,
with the task, each operator or method tried, the literal that failed and
their file:line:col."""

from __future__ import annotations

import json

import pytest

from conftest import run_htn

DOMAIN = """(defdomain ex (
  (:operator (!pick ?x) ((at ?x here) (light ?x)) ((at ?x here)) ((holding ?x)))
  (:operator (!drop ?x) ((holding ?x)) ((holding ?x)) ((at ?x there)))
  (:operator (!lock ?x) () () ((:protection (at ?x here))))
  (:operator (!take ?x) ((at ?x here)) ((at ?x here)) ((holding ?x)))
  (:method (move ?x) ((at ?x here)) ((!pick ?x) (!drop ?x)))
  (:method (move ?x ?to) ((at ?x here) (road here ?to)) ((!pick ?x) (!drop ?x)))
  (:method (guarded ?x) () ((!lock ?x) (!take ?x)))
  (:method (count ?n) more ((call > ?n 0)) ((!tick ?n) (count (call - ?n 1))))
  (:operator (!tick ?n) () () ())
  (:method (try ?x) ((at ?x here)) ((!take ?x) (!pick ?x)))
  (:method (try ?x) () ((!tick ?x)))
))
"""


def _explain(tmp_path, state: str, tasks: str, *flags):
    (tmp_path / "d.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text(f"(defproblem p ex ({state}) ({tasks}))\n")
    result = run_htn("plan", tmp_path / "d.jshop", tmp_path / "p.jshop", *flags)
    assert "Traceback" not in result.stderr
    result.stderr = result.stderr.replace(f"{tmp_path}/", "")
    return result


@pytest.mark.parametrize(
    "state,tasks,lines",
    [
        # missing fact: (light box) is not in the state
        (
            "(at box here)",
            "(move box)",
            [
                "task (!pick box) (d.jshop:6:39), after 0 step(s):",
                "operator (!pick ?x) (d.jshop:2:3): precondition (light box) has no satisfier "
                "[d.jshop:2:39]",
            ],
        ),
        # the one-argument method cannot take a two-argument task; the other fails
        (
            "(at box here) (light box)",
            "(move box there)",
            [
                "task (move box there) (p.jshop:1:48), after 0 step(s):",
                "method (move ?x) (d.jshop:6:3): its head takes 1 argument(s), the task has 2",
                "method (move ?x ?to), branch Method1Branch0 (d.jshop:7:26): precondition "
                "(road here there) has no satisfier [d.jshop:7:40]",
            ],
        ),
        # (!lock box) protects (at box here), which (!take box) would delete
        (
            "(at box here)",
            "(guarded box)",
            [
                "task (!take box) (d.jshop:8:41), after 1 step(s):",
                "operator (!take ?x) (d.jshop:5:3): it would delete the protected atom "
                "(at box here) (manual 3.9)",
            ],
        ),
        # a recursion without a base case runs out at (count 0)
        (
            "",
            "(count 2)",
            [
                "task (count 0.0) (d.jshop:9:57), after 2 step(s):",
                "method (count ?n), branch more (d.jshop:9:23): precondition (call > 0.0 0.0) has "
                "no satisfier [d.jshop:9:29]",
            ],
        ),
    ],
)
def test_no_plan_is_explained_at_the_deepest_dead_end(tmp_path, state, tasks, lines):
    result = _explain(tmp_path, state, tasks)
    assert result.returncode == 1
    err = [line.strip() for line in result.stderr.splitlines()]
    assert err[0].startswith("explain: the search got deepest at this dead end")
    assert err[1 : 1 + len(lines)] == lines


def test_explain_in_json_and_with_a_plan(tmp_path):
    result = _explain(tmp_path, "(at box here)", "(move box)", "-f", "json")
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["type"] for r in records] == ["stats"]  # JSON Lines: no plan, statistics
    deepest = records[-1]["explain"][0]["deepest"]
    assert deepest["task"] == "(!pick box)" and deepest["at"].endswith("d.jshop:6:39")
    assert deepest["attempts"][0]["literal_at"].endswith("d.jshop:2:39")
    # on request, also when there is a plan: the first (try box) method fails
    result = _explain(
        tmp_path, "(at box here) (light box)", "(try box)", "--explain", "-f", "jshop"
    )
    assert result.returncode == 0 and "(!tick box)" in result.stdout
    assert "task (!pick box) (d.jshop:11:49), after 1 step(s):" in result.stderr
    assert "precondition (at box here) has no satisfier [d.jshop:2:26]" in result.stderr


def test_explain_all_lists_every_dead_end(tmp_path):
    result = _explain(tmp_path, "(at box here)", "(move box) (count 1)", "--explain-all")
    assert result.returncode == 1
    assert "explain: 1 dead end(s), in the order met:" in result.stderr
