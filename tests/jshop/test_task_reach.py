"""Hierarchical reachability (:mod:`htn.jshop.search.task_reach`): what no
decomposition of the initial network can reach with the facts its own
actions add. Grounding uses it to prove that a problem has no plan, and
otherwise gives the searches the model it gave before. Checked on a
hand-made domain where every action can reach a fact the methods never can,
on random problems (no plan lost, none added) and on corpus instances (a
depth-first plan only uses what is reached; the model is unchanged)."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from test_splitting import problems, same_answer

from htn.jshop.readers.load import load_inputs
from htn.jshop.search.best_first import BestFirst
from htn.jshop.search.grounding import ground
from htn.jshop.search.planner import Planner
from htn.jshop.search.task_reach import reached

from conftest import SHARED

# `walk` takes the walker to any free cell; the methods only walk it along
# `next` links from where it stands (a - b - c), and `d` is free but off
# the line: the delete relaxation of the actions reaches (at d), the
# hierarchy does not
WALKER = """(define (domain walker)
  (:requirements :hierarchy :typing :method-preconditions)
  (:types cell)
  (:predicates (at ?c - cell) (free ?c - cell) (next ?a ?b - cell) (seen ?c - cell))
  (:task visit :parameters (?c - cell))
  (:task goto :parameters (?c - cell))
  (:method visit_it :parameters (?c - cell) :task (visit ?c)
    :ordered-subtasks (and (goto ?c) (look ?c)))
  (:method there :parameters (?c - cell) :task (goto ?c) :precondition (at ?c)
    :ordered-subtasks (and))
  (:method step :parameters (?c ?p ?n - cell) :task (goto ?c)
    :precondition (and (at ?p) (next ?p ?n))
    :ordered-subtasks (and (walk ?p ?n) (goto ?c)))
  (:action walk :parameters (?p ?n - cell) :precondition (and (at ?p) (free ?n))
    :effect (and (at ?n) (not (at ?p))))
  (:action look :parameters (?c - cell) :precondition (at ?c) :effect (seen ?c)))
"""


def _walker(tmp_path, target: str):
    (tmp_path / "d.hddl").write_text(WALKER)
    (tmp_path / "p.hddl").write_text(
        "(define (problem w) (:domain walker) (:objects a b c d - cell)\n"
        f"  (:htn :ordered-subtasks (and (visit {target})))\n"
        "  (:init (at a) (free a) (free b) (free c) (free d) (next a b) (next b c)))\n"
    )
    dom, prob = load_inputs(str(tmp_path / "d.hddl"), str(tmp_path / "p.hddl"))
    return dom, prob.instances[0]


def test_what_only_the_relaxed_actions_reach_is_not_reached(tmp_path):
    dom, inst = _walker(tmp_path, "d")
    whole = ground(dom, inst, reach=False)
    look_d = ("!look", ("d",))
    assert look_d in {(a.name, a.args) for a in whole.actions.values()}
    # the walker only walks the line from a
    facts, _methods, actions = reached(whole)
    walks = {whole.actions[t].args for t in actions if whole.actions[t].name == "!walk"}
    assert walks == {("a", "b"), ("b", "c")}
    at = {whole.facts[b][1] for b in range(len(whole.facts)) if facts >> b & 1}
    assert {("a",), ("b",), ("c",)} <= at and ("d",) not in at
    assert look_d not in {(whole.actions[t].name, whole.actions[t].args) for t in actions}
    # so the root task has no method left: there is no plan, and no search
    model = ground(dom, inst)
    (root,) = model.roots
    assert model.methods_of[root] == [] and whole.methods_of[root]
    search = BestFirst(dom, inst)
    assert next(search.plans(timeout=30), None) is None
    assert search.stats.expansions == 0
    # depth-first search agrees: it walks the line and finds no way to d
    assert next(Planner(dom, inst).plans(), None) is None


def test_what_the_hierarchy_reaches_is_kept(tmp_path):
    dom, inst = _walker(tmp_path, "c")
    plan = next(p for p in BestFirst(dom, inst).plans(timeout=30) if p is not None)
    assert [(s.name, s.args) for s in plan.steps] == [
        ("!walk", ("a", "b")),
        ("!walk", ("b", "c")),
        ("!look", ("c",)),
    ]


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_reachability_loses_no_plan_and_adds_none(case):
    same_answer(case, "reach")


CORPUS = SHARED / "corpus" / "ipc2020-to"


@pytest.mark.skipif(not CORPUS.is_dir(), reason="needs ../shared/corpus")
@pytest.mark.parametrize(
    "folder, problem, shrinks",
    [
        ("Blocksworld-GTOHP", "p05.hddl", True),  # 566 methods, 139 reached
        ("Depots", "p05.hddl", True),  # 2,617, 567 reached
        ("Rover-GTOHP", "p05.hddl", True),  # 759, 738 reached
        ("Transport", "pfile05.hddl", True),  # 113, 73 reached
    ],
)
def test_a_depth_first_plan_uses_only_what_is_reached(folder, problem, shrinks):
    dom, prob = load_inputs(str(CORPUS / folder / "domain.hddl"), str(CORPUS / folder / problem))
    inst = prob.instances[0]
    model = ground(dom, inst)
    _facts, methods, actions = reached(model)
    count = sum(len(ms) for ms in model.methods_of.values())
    assert (len(methods) < count) is shrinks
    plan = next(Planner(dom, inst).plans())
    kept = {(model.actions[t].name, model.actions[t].args) for t in actions}
    assert all((s.name, tuple(s.args)) in kept for s in plan.steps)


def _signature(model) -> tuple[set, set]:
    """The model's methods (task, method, subtasks) and actions, by name."""
    name = model.tasks
    methods = {
        (name[t], gm.method.name, tuple(name[s] for s in gm.body))
        for t, ms in model.methods_of.items()
        for gm in ms
    }
    return methods, {(a.name, a.args) for a in model.actions.values()}


@pytest.mark.skipif(not CORPUS.is_dir(), reason="needs ../shared/corpus")
@pytest.mark.parametrize(
    "domain, problem",
    [
        ("ipc2020-to/Depots/domain.hddl", "ipc2020-to/Depots/p05.hddl"),
        ("ipc2020-to/Childsnack/domain.hddl", "ipc2020-to/Childsnack/p05.hddl"),
        (
            "ipc2020-to-slow/Minecraft-Regular/domain.hddl",
            "ipc2020-to-slow/Minecraft-Regular/p-004-005-004-005.hddl",
        ),
        ("ipc-po/Transport/domain.hddl", "ipc-po/Transport/pfile02.hddl"),
    ],
)
def test_where_a_plan_is_possible_the_searches_get_the_model_as_before(domain, problem):
    corpus = SHARED / "corpus"
    dom, prob = load_inputs(str(corpus / domain), str(corpus / problem))
    inst = prob.instances[0]
    assert _signature(ground(dom, inst)) == _signature(ground(dom, inst, reach=False))


# found by test_commit_rule's random problems: the initial network names
# (t1) twice, and t2's method must bring in !a2, which adds p2
TWICE = """(define (domain rnd) (:requirements :hierarchy :negative-preconditions)
  (:predicates (p0) (p1) (p2) (p3))
  (:task t1 :parameters ()) (:task t2 :parameters ())
  (:method m1_0 :parameters () :task (t1) :precondition (not (p2)) :subtasks (and (s0 (t2))))
  (:method m1_1 :parameters () :task (t1) :precondition (p3) :subtasks (and (s0 (t2))))
  (:method m2_0 :parameters () :task (t2) :precondition () :subtasks (and (s0 (a2))))
  (:method m2_1 :parameters () :task (t2) :precondition (p0) :subtasks (and (s0 (a2))))
  (:action a0 :parameters () :precondition () :effect ())
  (:action a2 :parameters () :precondition (and (p3) (p1)) :effect (p2)))
"""
TWICE_PROBLEM = """(define (problem r1) (:domain rnd)
  (:htn :parameters () :subtasks (and (s0 (t1)) (s1 (a0)) (s2 (t1))))
  (:init (p0) (p1) (p2) (p3)))
"""


def test_a_task_named_twice_in_the_initial_network_keeps_its_plan(tmp_path):
    # the reachability kept the reached methods by id: grounding (t1) a
    # second time freed the first list of its methods, a method made later
    # could get one of their ids and pass as reached, and its subtask was
    # never grounded, so that "no plan" was answered now and then
    (tmp_path / "d.hddl").write_text(TWICE)
    (tmp_path / "p.hddl").write_text(TWICE_PROBLEM)
    dom, prob = load_inputs(str(tmp_path / "d.hddl"), str(tmp_path / "p.hddl"))
    inst = prob.instances[0]
    for _ in range(20):
        model = ground(dom, inst)
        assert sorted(a.name for a in model.actions.values()) == ["!a0", "!a2"]
        assert all(model.methods_of[t] for t in model.roots if t not in model.actions)
    plan = next(p for p in BestFirst(dom, inst).plans() if p is not None)
    assert [s.name for s in plan.steps] == ["!a2", "!a0", "!a2"]
