"""HDDL as the IPC 2020 total-order domains beyond the shared sample write it,
on small hand-made files, one construct each: infix ordering constraints
(Entertainment), ``:subtasks`` with no ``:ordering`` (Minecraft), a problem
naming another domain (Barman-BDI), keywords glued to parentheses
(Satellite, AssemblyHierarchical), and left recursion through a free
variable (Entertainment), which the loop check must bound. Every plan is
checked with ``htn validate``, in both formats, and with the competition's
verifier where it is installed."""

from __future__ import annotations

import json

from test_hddl import check_ipc_decomposition

from conftest import run_htn


def _plan(tmp_path, oracle, domain: str, problem: str, *extra):
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(domain)
    p.write_text(problem)
    plan_file = tmp_path / "plan.txt"
    result = run_htn("plan", d, p, "-f", "ipc", "-o", plan_file, "--timeout", "60", *extra)
    assert result.returncode == 0, result.stderr
    steps = [
        tuple(line.strip("()").replace("!", "", 1).split())
        for line in plan_file.read_text().splitlines()
        if line.startswith("(")
    ]
    check_ipc_decomposition(result.stdout, d, p, steps)
    valid = run_htn("validate", d, p, plan_file)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    (tmp_path / "plan.ipc").write_text(result.stdout)
    oracle.check(d, p, tmp_path / "plan.ipc")
    return result, steps


STEPS = """(define (domain steps)
  (:requirements :typing :hierarchy)
  (:types item)
  (:predicates (done ?i - item))
  (:task all :parameters ())
  (:method m-all
    :parameters ()
    :task (all)
    :subtasks (and (c (mark c)) (a (mark a)) (b (mark b)))
    :ordering (and (a < b) (b < c)))
  (:method m-pair
    :parameters ()
    :task (all)
    :subtasks (and (mark b) (mark a)))
  (:action mark :parameters (?i - item) :precondition (not (done ?i)) :effect (done ?i)))
"""

STEPS_PROBLEM = """(define (problem p) (:domain steps)
  (:objects a b c - item)
  (:htn :parameters () :subtasks (and (all))))
"""


def test_infix_ordering_constraints_order_the_subtasks(tmp_path, ipc_oracle):
    _, steps = _plan(tmp_path, ipc_oracle, STEPS, STEPS_PROBLEM)
    assert steps == [("mark", "a"), ("mark", "b"), ("mark", "c")]


def test_subtasks_without_ordering_are_taken_as_written(tmp_path, ipc_oracle):
    domain = (
        STEPS.replace("(:method m-all", "(:method m-unused")
        .replace(
            "(:task all :parameters ())", "(:task all :parameters ()) (:task none :parameters ())"
        )
        .replace(":task (all)\n    :subtasks (and (c", ":task (none)\n    :subtasks (and (c")
    )
    _, steps = _plan(tmp_path, ipc_oracle, domain, STEPS_PROBLEM)
    assert steps == [("mark", "b"), ("mark", "a")]


def test_a_problem_naming_another_domain_is_a_warning(tmp_path, ipc_oracle):
    problem = STEPS_PROBLEM.replace("(:domain steps)", "(:domain steps_htn)")
    result, steps = _plan(tmp_path, ipc_oracle, STEPS, problem)
    assert "p.hddl:1:" in result.stderr
    assert "problem 'p' names domain 'steps_htn', not 'steps'" in result.stderr
    assert len(steps) == 3


def test_keywords_glued_to_parentheses(tmp_path, ipc_oracle):
    domain = STEPS.replace(":precondition (not (done ?i))", ":precondition (not(done ?i))")
    problem = STEPS_PROBLEM.replace("(define (problem p)", "(define(problem p)")
    _, steps = _plan(tmp_path, ipc_oracle, domain, problem)
    assert len(steps) == 3


# Entertainment's shape: (link ?a ?c) is a link to some ?b and a link from it;
# ?b is free, so depth-first decomposition chains through every object
# before any action changes the state.
CHAIN = """(define (domain chain)
  (:requirements :typing :hierarchy :equality :negative-preconditions)
  (:types node)
  (:predicates (wire ?a ?b - node) (plugged ?a ?b - node))
  (:task link :parameters (?a ?c - node))
  (:task direct :parameters (?a ?c - node))
  (:task finish :parameters ())
  (:method link-direct
    :parameters (?a ?c - node)
    :task (link ?a ?c)
    :subtasks (and (direct ?a ?c)))
  (:method link-through
    :parameters (?a ?b ?c - node)
    :task (link ?a ?c)
    :precondition (and (not (= ?a ?b)) (not (= ?b ?c)))
    :subtasks (and (t1 (link ?a ?b)) (t2 (direct ?b ?c)))
    :ordering (and (t1 < t2)))
  (:method direct-plug
    :parameters (?a ?c - node)
    :task (direct ?a ?c)
    :precondition (and (wire ?a ?c) (not (plugged ?a ?c)))
    :subtasks (and (plug ?a ?c)))
  (:method finish-never
    :parameters (?a - node)
    :task (finish)
    :precondition (plugged ?a ?a)
    :subtasks ())
  (:action plug :parameters (?a ?c - node) :effect (plugged ?a ?c)))
"""


def _chain_problem(n: int, wires: list, tasks: str) -> str:
    nodes = " ".join(f"n{i}" for i in range(n))
    return (
        f"(define (problem p) (:domain chain) (:objects {nodes} - node)\n"
        f"  (:htn :parameters () :ordered-subtasks (and {tasks}))\n"
        f"  (:init {' '.join(f'(wire n{a} n{b})' for a, b in wires)}))\n"
    )


def test_left_recursion_through_a_free_variable_plans(tmp_path, ipc_oracle):
    problem = _chain_problem(8, [(i, i + 1) for i in range(7)], "(link n0 n7)")
    _, steps = _plan(tmp_path, ipc_oracle, CHAIN, problem)
    assert steps == [("plug", f"n{i}", f"n{i + 1}") for i in range(7)]


def test_left_recursion_through_a_free_variable_is_bounded(tmp_path):
    # every pair wired and a last task that fails: the search must try every
    # way to link n0 to n5 before it can say there is no plan
    wires = [(a, b) for a in range(6) for b in range(6) if a != b]
    (tmp_path / "d.hddl").write_text(CHAIN)
    (tmp_path / "p.hddl").write_text(_chain_problem(6, wires, "(link n0 n5) (finish)"))
    result = run_htn(
        "plan", tmp_path / "d.hddl", tmp_path / "p.hddl", "-f", "json", "--quiet", "--timeout", "60"
    )
    assert result.returncode == 1
    stats = json.loads(result.stdout.splitlines()[-1])
    assert stats["plans_found"] == 0 and not stats["timed_out"], stats
    # keyed on the task, (link n0 x) is refused below itself in the same
    # state: 848 expansions; keyed on the method instance (with the free ?b)
    # it was every chain of (intermediate, target) pairs: 1.7 million in 20 s
    assert stats["expansions"] < 5_000, stats
