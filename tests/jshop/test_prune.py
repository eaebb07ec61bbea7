"""Methods that cannot apply from the initial state (:mod:`htn.jshop.search.prune`):
which are pruned, that pruning never changes a plan or its tree, and what it
saves on Monroe."""

from __future__ import annotations

import pytest

from htn.jshop.readers.load import paired, parse_text
from htn.jshop.search.planner import Planner
from htn.jshop.search.prune import dead_methods

from conftest import SHARED, run_htn

DOMAIN = """
(define (domain d)
  (:requirements :typing :hierarchy)
  (:types place item - object)
  (:predicates (at ?p - place) (road ?a ?b - place) (danger ?a - place ?k - item)
               (done ?p - place) (kind ?p - place ?k - item))
  (:task visit :parameters (?p - place))
  (:task fix :parameters (?p - place))
  (:task repair :parameters (?p - place))
  (:task top :parameters ())
  (:method m-fix-danger :parameters (?p - place ?k - item) :task (fix ?p)
    :precondition (danger ?p ?k) :ordered-subtasks (mark ?p))
  (:method m-fix-kind :parameters (?p - place) :task (fix ?p)
    :precondition (kind ?p special) :ordered-subtasks (mark ?p))
  (:method m-fix-done :parameters (?p - place) :task (fix ?p)
    :precondition (done ?p) :ordered-subtasks ())
  (:method m-visit-fix :parameters (?p - place) :task (visit ?p)
    :ordered-subtasks (fix ?p))
  (:method m-visit-go :parameters (?p ?q - place) :task (visit ?p)
    :precondition (road ?q ?p) :ordered-subtasks (and (go ?q ?p) (mark ?p)))
  (:method m-visit-repair :parameters (?p - place) :task (visit ?p)
    :ordered-subtasks (repair ?p))
  (:method m-repair :parameters (?p - place ?k - item) :task (repair ?p)
    :precondition (danger ?p ?k) :ordered-subtasks (mark ?p))
  (:method m-top :parameters (?p - place) :task (top) :ordered-subtasks (visit ?p))
  (:action go :parameters (?a ?b - place) :precondition (and (at ?a) (road ?a ?b))
    :effect (and (not (at ?a)) (at ?b)))
  (:action mark :parameters (?p - place) :precondition (at ?p) :effect (done ?p)))
"""

PROBLEM = """
(define (problem p) (:domain d)
  (:objects a b - place special plain - item)
  (:htn :ordered-subtasks (top))
  (:init (at a) (road a b) (kind b plain)))
"""


def _inputs(problem: str = PROBLEM):
    dom = parse_text(DOMAIN, "d.hddl", None, "domain")
    prob = parse_text(problem, "p.hddl", None, "problem")
    return paired(dom, prob)


def _names(dom, dead) -> set[str]:
    return {dom.methods[task][i].branches[0].label for task, i in dead}


def test_a_method_needing_a_static_fact_nobody_states_is_pruned():
    dom, prob = _inputs()
    dead = dead_methods(dom, prob.instances[0])
    # no (danger ...) at all; (kind ?p special) with the constant: only (kind b plain)
    assert _names(dom, dead) >= {"m-fix-danger", "m-fix-kind", "m-repair"}


def test_a_fact_that_matches_keeps_the_method_and_a_changed_predicate_is_never_static():
    dom, prob = _inputs(PROBLEM.replace("(kind b plain)", "(kind b special) (danger b plain)"))
    assert dead_methods(dom, prob.instances[0]) == set()
    # (done ?p) is added by mark: not static, though no fact states it
    assert "m-fix-done" not in _names(dom, dead_methods(dom, _inputs()[1].instances[0]))


def test_a_task_that_cannot_be_done_kills_the_methods_that_need_it():
    # repair has one method, which needs a (danger ...): m-visit-repair, which
    # needs repair, goes with it
    dom, prob = _inputs()
    assert _names(dom, dead_methods(dom, prob.instances[0])) == {
        "m-fix-danger",
        "m-fix-kind",
        "m-repair",
        "m-visit-repair",
    }
    # without roads, go can never apply: m-visit-go needs a road itself; fix is
    # still doable through (done ?p), which mark adds (at is not static: go
    # changes it), so m-visit-fix and m-top stay
    dom, prob = _inputs(PROBLEM.replace("(road a b)", ""))
    assert _names(dom, dead_methods(dom, prob.instances[0])) == {
        "m-fix-danger",
        "m-fix-kind",
        "m-repair",
        "m-visit-repair",
        "m-visit-go",
    }


def _first(dom, prob, prune: bool):
    planner = Planner(dom, prob.instances[0], record_trees=True, prune=prune)
    plan = next(p for p in planner.plans() if p is not None)
    return plan, planner


def test_the_plan_and_its_tree_are_the_unpruned_search_s():
    dom, prob = _inputs()
    plan, planner = _first(dom, prob, prune=True)
    same, unpruned = _first(dom, prob, prune=False)
    assert planner.pruned == 4 and unpruned.pruned == 0
    assert [str(s) for s in plan.steps] == [str(s) for s in same.steps]
    # the tree names each method by its place in the domain (m-visit-go: method 2)
    assert plan.tree.to_text() == same.tree.to_text()
    assert "[method visit#2 branch m-visit-go]" in plan.tree.to_text()
    assert planner.stats.expansions < unpruned.stats.expansions


MONROE = SHARED / "corpus" / "ipc2020-to-slow" / "Monroe-Fully-Observable"
PFILE05 = MONROE / "pfile05-p-0090-quell-riot-7-tlt"


@pytest.mark.corpus
def test_monroe_loses_its_impossible_methods_and_keeps_its_plan(tmp_path, ipc_oracle):
    domain, problem = f"{PFILE05}-domain.hddl", f"{PFILE05}.hddl"
    if not MONROE.is_dir():
        pytest.skip(f"{MONROE} not found")
    from htn.jshop.readers.load import load_inputs

    dom, prob = load_inputs(domain, problem)
    dead = dead_methods(dom, prob.instances[0])
    assert len(dead) == 21 and sum(map(len, dom.methods.values())) == 72
    assert {"clean_up_hazard", "clear_road_hazard", "plow_road"} <= {t for t, _ in dead}
    r = run_htn("plan", domain, problem, "-f", "ipc")
    assert r.returncode == 0, r.stderr
    (tmp_path / "plan.ipc").write_text(r.stdout)
    ipc_oracle.check(domain, problem, tmp_path / "plan.ipc")
