"""A long-lived unified-planning engine keeps memory flat over many domains
(issue 35): the compiled code of a problem's domain is forgotten once it is
solved (``clear_caches``), and what the caches keep is bounded.

50 different small hierarchical problems (each its own domain) are solved
in one process; from the 10th to the 50th, traced memory (``tracemalloc``,
after ``gc.collect()``) may grow by at most 0.25 MB more than UP's own
parsing of the same 50 problems grows it in another process."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("unified_planning")

from conftest import ROOT  # noqa: E402

DOMAIN = """(define (domain mini{i})
  (:requirements :hierarchy :typing :negative-preconditions)
  (:types package vehicle - thing place thing - object)
  (:predicates (at{i} ?x - thing ?l - place) (road{i} ?a - place ?b - place)
               (in{i} ?p - package ?v - vehicle))
  (:task deliver{i} :parameters (?p - package ?to - place))
  (:task go{i} :parameters (?v - vehicle ?to - place))
  (:method m-deliver{i} :parameters (?p - package ?v - vehicle ?a - place ?b - place)
    :task (deliver{i} ?p ?b)
    :precondition (at{i} ?p ?a)
    :ordered-subtasks (and (go{i} ?v ?a) (load{i} ?v ?a ?p) (go{i} ?v ?b) (unload{i} ?v ?b ?p)))
  (:method m-here{i} :parameters (?v - vehicle ?l - place) :task (go{i} ?v ?l)
    :precondition (at{i} ?v ?l) :ordered-subtasks (and))
  (:method m-drive{i} :parameters (?v - vehicle ?a - place ?b - place) :task (go{i} ?v ?b)
    :precondition (at{i} ?v ?a) :ordered-subtasks (and (drive{i} ?v ?a ?b)))
  (:action drive{i} :parameters (?v - vehicle ?a - place ?b - place)
    :precondition (and (at{i} ?v ?a) (road{i} ?a ?b))
    :effect (and (not (at{i} ?v ?a)) (at{i} ?v ?b)))
  (:action load{i} :parameters (?v - vehicle ?l - place ?p - package)
    :precondition (and (at{i} ?v ?l) (at{i} ?p ?l))
    :effect (and (not (at{i} ?p ?l)) (in{i} ?p ?v)))
  (:action unload{i} :parameters (?v - vehicle ?l - place ?p - package)
    :precondition (and (at{i} ?v ?l) (in{i} ?p ?v))
    :effect (and (not (in{i} ?p ?v)) (at{i} ?p ?l))))
"""
PROBLEM = """(define (problem mini{i}-1) (:domain mini{i})
  (:objects p1 p2 - package truck - vehicle a b c - place)
  (:htn :ordered-subtasks (and (deliver{i} p1 b) (deliver{i} p2 c)))
  (:init (at{i} p1 a) (at{i} p2 b) (at{i} truck c) (road{i} c a) (road{i} a b) (road{i} b c)
         (road{i} b a)))
"""

SCRIPT = """
import gc, os, sys, tracemalloc
import htn.up  # noqa: F401  (registers the engine)
from unified_planning.io import PDDLReader
from unified_planning.shortcuts import OneshotPlanner, get_environment
get_environment().credits_stream = None
folder, solve = sys.argv[1], sys.argv[2] == "solve"
marks = {}
tracemalloc.start()
for i in range(50):
    problem = PDDLReader().parse_problem(os.path.join(folder, f"d{i}.hddl"),
                                         os.path.join(folder, f"p{i}.hddl"))
    if solve:
        with OneshotPlanner(name="htn", params={"search": ["dfs", "gbfs"][i % 2]}) as planner:
            result = planner.solve(problem, timeout=60)
        assert result.plan is not None and len(result.plan.action_plan.actions) == 7, \\
            result.status
        del result
    del problem
    gc.collect()
    if i + 1 in (10, 50):
        marks[i + 1] = tracemalloc.get_traced_memory()[0]
print(marks[50] - marks[10])
"""


@pytest.mark.slow
def test_memory_stays_flat_over_fifty_domains(tmp_path):
    for i in range(50):
        (tmp_path / f"d{i}.hddl").write_text(DOMAIN.replace("{i}", str(i)))
        (tmp_path / f"p{i}.hddl").write_text(PROBLEM.replace("{i}", str(i)))

    def growth(mode: str) -> int:
        r = subprocess.run(
            [sys.executable, "-c", SCRIPT, str(tmp_path), mode],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert r.returncode == 0, r.stderr[-2000:]
        return int(r.stdout.split()[-1])

    parsing, solving = growth("parse"), growth("solve")
    extra = (solving - parsing) / 2**20
    assert extra <= 0.25, (
        f"the engine grew memory by {solving / 2**20:.2f} MB, UP's parsing "
        f"by {parsing / 2**20:.2f} MB"
    )
