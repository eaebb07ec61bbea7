"""Conjunctions compiled per binding mode (htn.jshop.modes) find the same
satisfiers in the same order as JSHOP2's left-to-right backtracking: fact
axioms stated twice give two satisfiers, an atom of another length is not a
match, a call with an unbound variable holds, and a call that fails inline
is reported at its place. (The JSHOP2 golden tests check the corpus.)"""
from __future__ import annotations

from conftest import run_htn

DOMAIN = """(defdomain m (
  (:operator (!pick ?x ?y) () () ())
  (:- (color red) nil) (:- (color red) nil) (:- (color blue) nil)
  (:method (go) ((p ?x) (color ?y) (not (q ?x ?y)) (call > ?n 0)) ((!pick ?x ?y)))
  (:method (bad) ((p ?x) (call = (call + ?x 1) 2)) ((!pick ?x ?x)))
))
"""


def test_satisfiers_and_their_order(tmp_path):
    (tmp_path / "d.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text("(defproblem p m ((p a) (p b 1) (p c) (q a blue)) ((go)))\n")
    result = run_htn("plan", tmp_path / "d.jshop", tmp_path / "p.jshop", "--all", "-f", "jshop")
    assert result.returncode == 0, result.stderr
    steps = [line for line in result.stdout.splitlines() if line.startswith("(")]
    assert steps == ["(!pick a red)", "(!pick a red)", "(!pick c red)", "(!pick c red)",
                     "(!pick c blue)"]


def test_a_failing_call_is_reported_at_its_place(tmp_path):
    (tmp_path / "d.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text("(defproblem p m ((p a)) ((bad)))\n")
    result = run_htn("plan", tmp_path / "d.jshop", tmp_path / "p.jshop")
    assert result.returncode == 2
    assert result.stderr.startswith(f"{tmp_path / 'd.jshop'}:5:34: call +: expected a number, "
                                    "got a")
