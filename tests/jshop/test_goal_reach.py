"""The goal-reachability cut of the heuristic search
(:mod:`htn.jshop.search.goal_reach`): a node is cut where the actions its
network can still bring in cannot make the goal true. That no node on a
plan's path is cut is tested on corpus instances in ``test_goal_chain.py``,
for both goal cuts."""

from __future__ import annotations

from htn.jshop.readers.load import load_inputs
from htn.jshop.search import grounding
from htn.jshop.search.best_first import BestFirst, _apply
from htn.jshop.search.goal_reach import GoalReach

# Each part is sanded and painted by its own task; the goal wants a blue
# and b red. Once a is painted red, only `process a` could sand it again.
DOMAIN = """(define (domain paint) (:requirements :hierarchy :typing)
  (:types part)
  (:predicates (raw ?p - part) (red ?p - part) (blue ?p - part))
  (:task process :parameters (?p - part))
  (:method m_red :parameters (?p - part) :task (process ?p)
    :ordered-subtasks (and (sand ?p) (paint_red ?p)))
  (:method m_blue :parameters (?p - part) :task (process ?p)
    :ordered-subtasks (and (sand ?p) (paint_blue ?p)))
  (:action sand :parameters (?p - part)
    :effect (and (raw ?p) (not (red ?p)) (not (blue ?p))))
  (:action paint_red :parameters (?p - part) :precondition (raw ?p)
    :effect (and (red ?p) (not (raw ?p))))
  (:action paint_blue :parameters (?p - part) :precondition (raw ?p)
    :effect (and (blue ?p) (not (raw ?p)))))
"""
PROBLEM = """(define (problem two) (:domain paint)
  (:objects a b - part)
  (:htn :ordered-subtasks (and (process a) (process b)))
  (:init)
  (:goal (and (blue a) (red b))))
"""


def _model(tmp_path):
    (tmp_path / "d.hddl").write_text(DOMAIN)
    (tmp_path / "p.hddl").write_text(PROBLEM)
    dom, prob = load_inputs(str(tmp_path / "d.hddl"), str(tmp_path / "p.hddl"))
    return dom, prob.instances[0], grounding.ground(dom, prob.instances[0])


def test_a_goal_fact_no_task_left_can_bring_back_cuts_the_node(tmp_path):
    _dom, _inst, model = _model(tmp_path)
    cut = GoalReach(model)
    assert cut.active
    task = {model.tasks[t]: t for t in range(len(model.tasks))}
    act = {(a.name, a.args): a for a in model.actions.values()}
    proc_a, proc_b = task[("process", ("a",))], task[("process", ("b",))]
    # from the start, sanding comes first: the full fixpoint finds the goal
    assert cut.ok(model.init, (proc_a, proc_b))
    red_a = _apply(act[("!paint_red", ("a",))], _apply(act[("!sand", ("a",))], model.init))
    blue_a = _apply(act[("!paint_blue", ("a",))], _apply(act[("!sand", ("a",))], model.init))
    # a painted red: `process b` cannot make it blue; `process a` still could
    assert not cut.ok(red_a, (proc_b,))
    assert cut.ok(red_a, (proc_a, proc_b))
    assert cut.ok(blue_a, (proc_b,))
    # b left unpainted with nothing to do: its fact has no action below
    assert not cut.ok(blue_a, ())


def test_gbfs_plans_with_the_cut_and_counts_it(tmp_path):
    dom, inst, model = _model(tmp_path)
    search = BestFirst(dom, inst)
    search._prepared(model)
    assert search.cut is not None
    plan = next(p for p in search.plans(timeout=30) if p is not None)
    # `m_red` for a is cut as it is generated: its body has no paint_blue
    assert search.stats.goal_cuts >= 1
    assert [(s.name, s.args) for s in plan.steps] == [
        ("!sand", ("a",)),
        ("!paint_blue", ("a",)),
        ("!sand", ("b",)),
        ("!paint_red", ("b",)),
    ]


def test_no_goal_no_cut(tmp_path):
    (tmp_path / "d.hddl").write_text(DOMAIN)
    (tmp_path / "p.hddl").write_text(PROBLEM.replace("(:goal (and (blue a) (red b)))", ""))
    dom, prob = load_inputs(str(tmp_path / "d.hddl"), str(tmp_path / "p.hddl"))
    model = grounding.ground(dom, prob.instances[0])
    assert not GoalReach(model).active
    search = BestFirst(dom, prob.instances[0])
    search.prepare()
    assert search.model is not None and search.cut is None
