"""Partial-order HDDL (``:subtasks`` with no ``:ordering`` or with a partial
``:ordering``): tasks with no unfinished predecessor may be done in any
order, by every search (``--search dfs|gbfs|wastar|auto``). Every plan is
checked with ``htn validate`` and, when the binary is there, with the
competition's verifier (pandaPIparser)."""

from __future__ import annotations

import json
import subprocess

import pytest

from htn.jshop.language.syntax import PartialOrder
from htn.jshop.readers.hddl import parse_model
from htn.jshop.readers.hddl_order import subtask_order

from conftest import SHARED, run_htn

PANDA = SHARED / "tools" / "pandaPIparser" / "pandaPIparser"
SEARCHES = ["dfs", "gbfs", "wastar", "auto"]

# ipc-po's README: only b before a is executable; no :ordering leaves them unordered
PROBE = """(define (domain probe)
  (:requirements :hierarchy)
  (:predicates (p))
  (:task t :parameters ())
  (:method m :parameters () :task (t)
    :subtasks (and (t0 (a)) (t1 (b))))
  (:action a :parameters () :precondition (p) :effect ())
  (:action b :parameters () :precondition () :effect (p)))
"""
PROBE_PROBLEM = """(define (problem probe1) (:domain probe)
  (:htn :parameters () :subtasks (and (t)))
  (:init))
"""

# an N-shaped order (a < c, b < c, b < d) that no series-parallel nesting
# writes; c needs what a and b make, d undoes what c needs unless c is first
N_SHAPE = """(define (domain nshape)
  (:requirements :hierarchy :negative-preconditions)
  (:predicates (pa) (pb) (pc) (blocked))
  (:task t :parameters ())
  (:method m :parameters () :task (t)
    :subtasks (and (x (d)) (y (c)) (z (a)) (w (b)))
    :ordering (and (z < y) (w < y) (w < x)))
  (:action a :parameters () :precondition () :effect (pa))
  (:action b :parameters () :precondition () :effect (pb))
  (:action c :parameters () :precondition (and (pa) (pb) (not (blocked))) :effect (pc))
  (:action d :parameters () :precondition () :effect (blocked)))
"""
N_PROBLEM = """(define (problem n1) (:domain nshape)
  (:htn :parameters () :subtasks (and (t)))
  (:init)
  (:goal (pc)))
"""

# two unordered tasks of the initial network that must interleave
INTERLEAVE = """(define (domain inter)
  (:requirements :hierarchy :typing)
  (:types k)
  (:predicates (got ?k - k) (used ?k - k))
  (:task job :parameters (?k - k))
  (:method m-job :parameters (?k - k ?o - k) :task (job ?k)
    :ordered-subtasks (and (get ?k) (use ?k ?o)))
  (:action get :parameters (?k - k) :effect (got ?k))
  (:action use :parameters (?k ?o - k) :precondition (and (got ?k) (got ?o))
    :effect (used ?k)))
"""
INTERLEAVE_PROBLEM = """(define (problem i1) (:domain inter)
  (:objects k1 k2 - k)
  (:htn :parameters () :subtasks (and (j1 (job k1)) (j2 (job k2))))
  (:init)
  (:goal (and (used k1) (used k2))))
"""


def _plan(tmp_path, domain: str, problem: str, search: str) -> list:
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(domain)
    p.write_text(problem)
    jshop = tmp_path / "plan.txt"
    result = run_htn("plan", d, p, "-f", "ipc", "-o", jshop, "--search", search, "-q")
    assert result.returncode == 0, result.stderr
    valid = run_htn("validate", d, p, jshop)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    if PANDA.is_file():
        ipc = tmp_path / "plan.ipc"
        ipc.write_text(result.stdout)
        verdict = subprocess.run(
            [str(PANDA), "-C", "--verify", str(d), str(p), str(ipc)], capture_output=True, text=True
        )
        assert "Plan verification result: true" in verdict.stdout, result.stdout
    return [line.split()[1] for line in result.stdout.split("root")[0].splitlines()[1:]]


@pytest.mark.parametrize("search", SEARCHES)
def test_unordered_subtasks_are_planned_in_an_order_that_works(tmp_path, search):
    assert _plan(tmp_path, PROBE, PROBE_PROBLEM, search) == ["b", "a"]


@pytest.mark.parametrize("search", SEARCHES)
def test_a_partial_order_that_is_not_series_parallel(tmp_path, search):
    steps = _plan(tmp_path, N_SHAPE, N_PROBLEM, search)
    assert sorted(steps) == ["a", "b", "c", "d"]
    assert steps.index("c") < steps.index("d") and steps.index("b") < steps.index("d")


@pytest.mark.parametrize("search", SEARCHES)
def test_tasks_of_the_initial_network_interleave(tmp_path, search):
    steps = _plan(tmp_path, INTERLEAVE, INTERLEAVE_PROBLEM, search)
    assert steps[:2] in (["get", "get"],) or steps.count("get") == 2
    assert sorted(steps) == ["get", "get", "use", "use"]


def test_the_order_read_from_hddl():
    model = parse_model(N_SHAPE, "d.hddl")
    subtasks, order = subtask_order(model.methods[0].network, "m", None)
    assert [s.label for s in subtasks] == ["z", "w", "x", "y"]  # topological, as written
    assert type(order) is PartialOrder and not order
    assert tuple(order) == ((), (), (1,), (0, 1))
    probe = parse_model(PROBE, "d.hddl")
    assert subtask_order(probe.methods[0].network, "m", None)[1] is False
    chain = N_SHAPE.replace("(and (z < y) (w < y) (w < x))", "(and (z < w) (w < x) (x < y))")
    network = parse_model(chain, "d.hddl").methods[0].network
    assert subtask_order(network, "m", None)[1] is True


def test_auto_says_which_search_found_the_plan(tmp_path):
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(PROBE)
    p.write_text(PROBE_PROBLEM)
    result = run_htn("plan", d, p, "-f", "json", "--search", "auto")
    stats = json.loads(result.stdout.splitlines()[-1])
    assert stats["found_by"] in ("dfs", "gbfs")


def test_heuristic_search_refuses_all(tmp_path):
    d, p = tmp_path / "d.hddl", tmp_path / "p.hddl"
    d.write_text(PROBE)
    p.write_text(PROBE_PROBLEM)
    result = run_htn("plan", d, p, "--search", "gbfs", "--all")
    assert result.returncode == 2 and "--all needs --search dfs" in result.stderr


@pytest.mark.corpus
def test_a_no_plan_the_loop_check_may_have_caused_says_so(tmp_path):
    """PCP interleaves two recursive grammars whose actions flip a turn back
    and forth: the state repeats while the plan makes progress, so the loop
    check cuts every plan; depth-first search says so beside "no plan", and
    the heuristic search (no loop check) finds one."""
    folder = SHARED / "corpus" / "ipc-po" / "PCP"
    d, p = folder / "p-pcp11-domain.hddl", folder / "p-pcp11.hddl"
    if not d.is_file():
        pytest.skip(f"{folder} not found")
    result = run_htn("plan", d, p)
    assert result.returncode == 1
    assert "the loop check cut" in result.stderr and "--search auto" in result.stderr
    stats = json.loads(run_htn("plan", d, p, "-f", "json", "-q").stdout.splitlines()[-1])
    assert stats["loop_cuts"] > 0
    result = run_htn("plan", d, p, "--search", "auto", "-f", "ipc")
    assert result.returncode == 0 and result.stdout.startswith("==>"), result.stderr
