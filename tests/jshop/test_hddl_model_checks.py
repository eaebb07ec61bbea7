"""HDDL models that cannot be meant are located errors when the domain is
read (issue 34): arity slips in a method's task, subtasks and ordering
labels (before the pull-up of preconditions, which indexed a task's
parameters by a subtask's arguments and crashed), a parameter declared
twice in a task, and a cycle in ``:types``."""

from __future__ import annotations

import pytest

from conftest import run_htn

DOMAIN = """(define (domain d)
  (:types ta tb - object)
  (:predicates (p ?x))
  (:task t :parameters (?a))
  (:task top :parameters ())
  (:action a :parameters (?x) :precondition (p ?x))
  (:method mt :parameters (?a ?b) :task (t ?a) :ordered-subtasks (a ?b))
  (:method mtop :parameters (?y) :task (top) :ordered-subtasks (t ?y)))
"""
PROBLEM = (
    "(define (problem pr) (:domain d) (:objects o) (:htn :ordered-subtasks (top)) (:init (p o)))"
)

# (what is wrong, the text replaced, its replacement, words of the message)
SLIPS = [
    (
        "a method's task has more arguments than the task declares (the issue's case)",
        ":task (t ?a)",
        ":task (t ?a ?b)",
        "t takes 1 argument(s), given 2",
    ),
    ("a method's task has fewer", ":task (t ?a)", ":task (t)", "t takes 1 argument(s), given 0"),
    (
        "a subtask's action has more",
        ":ordered-subtasks (a ?b)",
        ":ordered-subtasks (a ?b ?a)",
        "a takes 1 argument(s), given 2",
    ),
    (
        "a subtask's task has fewer",
        ":ordered-subtasks (t ?y)",
        ":ordered-subtasks (t)",
        "t takes 1 argument(s), given 0",
    ),
    (
        "a subtask names nothing declared",
        ":ordered-subtasks (t ?y)",
        ":ordered-subtasks (nothing ?y)",
        "unknown task nothing",
    ),
    (
        "two subtasks share a label",
        ":ordered-subtasks (t ?y)",
        ":subtasks (and (s1 (t ?y)) (s1 (t ?y))) :ordering (and (s1 < s1))",
        "label s1 is given to two subtasks",
    ),
    (
        "an ordering names no label",
        ":ordered-subtasks (t ?y)",
        ":subtasks (and (s1 (t ?y)) (s2 (t ?y))) :ordering (and (s1 < s3))",
        "no subtask is labelled s3",
    ),
    (
        "an ordering with a cycle",
        ":ordered-subtasks (t ?y)",
        ":subtasks (and (s1 (t ?y)) (s2 (t ?y))) :ordering (and (s1 < s2) (s2 < s1))",
        "the ordering constraints form a cycle",
    ),
    (
        "a task declares a parameter twice",
        "(:task t :parameters (?a))",
        "(:task t :parameters (?a ?a))",
        "task t: parameter ?a is declared twice",
    ),
    (
        "a type is its own supertype through another",
        "(:types ta tb - object)",
        "(:types ta - tb tb - ta)",
        "type ta is its own supertype: ta - tb - ta",
    ),
    (
        "a cycle of three types",
        "(:types ta tb - object)",
        "(:types ta - tb tb - tc tc - ta)",
        "is its own supertype",
    ),
    (
        "a type declared as its own supertype",
        "(:types ta tb - object)",
        "(:types ta - ta)",
        "type ta is its own supertype: ta - ta",
    ),
]


def test_the_unmutated_domain_plans(tmp_path):
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(DOMAIN)
    p.write_text(PROBLEM)
    r = run_htn("plan", d, p)
    assert r.returncode == 0 and "(!a o)" in r.stdout, r.stderr


@pytest.mark.parametrize("what,old,new,words", SLIPS, ids=[s[0] for s in SLIPS])
@pytest.mark.parametrize("command", ["plan", "stats", "transform", "validate"])
def test_a_model_slip_is_a_located_error_of_every_command(tmp_path, what, old, new, words, command):
    assert old in DOMAIN
    d, p, plan = tmp_path / "d.hddl", tmp_path / "p.hddl", tmp_path / "plan.txt"
    d.write_text(DOMAIN.replace(old, new, 1))
    p.write_text(PROBLEM)
    plan.write_text("==>\n0 a o\nroot 1\n1 top -> mtop 2\n2 t o -> mt 0\n<==\n")
    args = {"plan": [d, p], "stats": [d, p], "transform": [d, p], "validate": [d, p, plan]}[command]
    r = run_htn(command, *args)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert "Traceback" not in r.stderr
    first = r.stderr.splitlines()[0]
    assert first.startswith(f"{d}:") and words in first, first
    line, col = first[len(str(d)) + 1 :].split(":")[:2]
    assert int(line) > 0 and int(col) > 0


def test_a_slip_in_the_problems_network_is_located_in_the_problem(tmp_path):
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(DOMAIN)
    p.write_text(
        "(define (problem pr) (:domain d) (:objects o) (:htn :parameters (?z) "
        ":subtasks (and (x1 (t ?z)) (x1 (top))) :ordering (and (x1 < x1))) "
        "(:init (p o)))"
    )
    r = run_htn("plan", d, p)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert r.stderr.startswith(f"{p}:1:") and "label x1 is given to two" in r.stderr
