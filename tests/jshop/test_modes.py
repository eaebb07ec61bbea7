"""Conjunctions compiled per binding mode (htn.jshop.logic.modes) find the same
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
    assert steps == [
        "(!pick a red)",
        "(!pick a red)",
        "(!pick c red)",
        "(!pick c red)",
        "(!pick c blue)",
    ]


def test_a_failing_call_is_reported_at_its_place(tmp_path):
    (tmp_path / "d.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text("(defproblem p m ((p a)) ((bad)))\n")
    result = run_htn("plan", tmp_path / "d.jshop", tmp_path / "p.jshop")
    assert result.returncode == 2
    assert result.stderr.startswith(
        f"{tmp_path / 'd.jshop'}:5:34: call +: expected a number, got a"
    )


LISTS = """(defdomain m (
  (:operator (!pick ?x ?y) () () ())
  (:method (find) ((g (on ?x ?y)) (g (at ?y ?x)) (not (g (on ?y ?x)))) ((!pick ?x ?y)))
  (:method (same) ((g (on ?x ?x))) ((!pick ?x ?x)))
))
"""


def test_list_arguments_match_element_by_element(tmp_path):
    # the second (find) and (same) run the compiled code: a list argument
    # matches lists of its length only, nil binds a variable, a repeated
    # variable must be equal, a negated list atom fails on a match
    (tmp_path / "d.jshop").write_text(LISTS)
    (tmp_path / "p.jshop").write_text(
        "(defproblem p m ((g (on a b)) (g (on a b c)) (g on) (g (on c c)) (g (at b a))"
        " (g (on nil d)) (g (at d nil)) (g (on e f)) (g (at f e)) (g (on f e)))"
        " ((find) (find) (same) (same)))\n"
    )
    result = run_htn("plan", tmp_path / "d.jshop", tmp_path / "p.jshop", "--all", "-f", "jshop")
    assert result.returncode == 0, result.stderr
    steps = [line for line in result.stdout.splitlines() if line.startswith("(")]
    finds = [
        ("(!pick a b)", "(!pick a b)"),
        ("(!pick a b)", "(!pick NIL d)"),
        ("(!pick NIL d)", "(!pick a b)"),
        ("(!pick NIL d)", "(!pick NIL d)"),
    ]
    assert steps == [s for pair in finds for s in (*pair, "(!pick c c)", "(!pick c c)")]


def test_a_call_failing_in_compiled_code_is_reported_at_its_place(tmp_path):
    # the second (sum 3) runs the compiled code, where (call + a 1) fails
    (tmp_path / "d.jshop").write_text(
        "(defdomain m (\n  (:operator (!pick ?x ?y) () () ())\n"
        "  (:method (sum ?y) ((p ?x) (call = (call + ?x 1) ?y)) ((!pick ?x ?y)))))\n"
    )
    (tmp_path / "p.jshop").write_text("(defproblem p m ((p 1) (p a)) ((sum 2) (sum 3)))\n")
    result = run_htn("plan", tmp_path / "d.jshop", tmp_path / "p.jshop")
    assert result.returncode == 2
    assert result.stderr.startswith(
        f"{tmp_path / 'd.jshop'}:3:37: call +: expected a number, got a"
    )
