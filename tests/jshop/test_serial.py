"""GBFS that finishes a started member of an unordered group before the
others (``BestFirst(serial=True)``, a member of ``--search auto``): every
plan it finds is a plan of the partial order (htn's decomposition check and
pandaPIparser), it skips the interleavings that lead nowhere on ipc-po
Rover, and where a plan needs an interleaving it finds none and the
portfolio goes on."""

from __future__ import annotations

import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from test_commit_rule import _check_plan, problems
from test_partial_order import INTERLEAVE, INTERLEAVE_PROBLEM

from htn.api.inputs import function_table, read_inputs
from htn.jshop.language.syntax import PartialOrder
from htn.jshop.search.best_first import BestFirst
from htn.jshop.search.task_networks import body_items, firsts, serialize

from conftest import SHARED, run_htn


def test_the_member_entered_is_taken_out_in_front():
    # three members, the third after the first: (1 2) | (3) | (4), 4 after 1 2
    net = body_items((0, 1, 2), PartialOrder(((), (), (0,))))
    net = (((1, 2), (3,), (4,)), net[0][1]), 9
    got, path = serialize(net, (1,))
    assert path == () and got == (3, (((1, 2), (4,)), (0, 1)), 9)
    assert [t for _, t in firsts(got)] == [3]
    got, _ = serialize(net, (0,))  # 1 2 first; 3 and 4 unordered after them
    assert got == (1, 2, (((3,), (4,)), (0, 0)), 9)


def _search(folder: Path, domain: str, problem: str, serial: bool):
    (folder / "d.hddl").write_text(domain)
    (folder / "p.hddl").write_text(problem)
    inputs = read_inputs(folder / "d.hddl", folder / "p.hddl", function_table(None))
    search = BestFirst(inputs.domain, inputs.problem.instances[0], serial=serial)
    plan = next((p for p in search.plans(timeout=20) if p is not None), None)
    return inputs, plan, search


@settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(problems())
def test_every_plan_it_finds_is_a_plan_of_the_partial_order(case):
    domain, problem = case
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        inputs, plan, search = _search(folder, domain, problem, serial=True)
        if plan is not None:
            _check_plan(folder, inputs.domain, inputs.problem, plan, search)
        else:  # it may miss plans: the complete search decides
            _search(folder, domain, problem, serial=False)


NEEDS_INTERLEAVING = INTERLEAVE.replace(
    ":precondition (and (got ?k) (got ?o))", ":precondition (and (got ?k) (got ?o) (not (= ?k ?o)))"
).replace("(:requirements :hierarchy :typing)", "(:requirements :hierarchy :typing :equality)")


def test_a_plan_that_needs_an_interleaving(tmp_path):
    """Each job uses the other's part: the two gets come before both uses.
    Serial search runs out of moves; the complete one and auto plan it."""
    _, plan, search = _search(tmp_path, NEEDS_INTERLEAVING, INTERLEAVE_PROBLEM, serial=True)
    assert plan is None and not search.stats.timed_out
    _, plan, _ = _search(tmp_path, NEEDS_INTERLEAVING, INTERLEAVE_PROBLEM, serial=False)
    assert [s.name for s in plan.steps][:2] == ["!get", "!get"]
    r = run_htn("plan", tmp_path / "d.hddl", tmp_path / "p.hddl", "--search", "auto")
    assert r.returncode == 0, r.stderr


@pytest.mark.corpus
def test_rover_is_planned_one_goal_after_the_other(tmp_path):
    folder = SHARED / "corpus" / "ipc-po" / "Rover"
    if not folder.is_dir():
        pytest.skip(f"{folder} not found")
    domain, problem = (folder / "domain.hddl").read_text(), (folder / "pfile04.hddl").read_text()
    inputs, plan, search = _search(tmp_path, domain, problem, serial=True)
    assert plan is not None and search.stats.expansions < 1000
    _check_plan(tmp_path, inputs.domain, inputs.problem, plan, search)
