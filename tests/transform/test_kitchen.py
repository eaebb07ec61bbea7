"""The kitchen pick-and-place domain (groundwork for plan transformations)."""

from __future__ import annotations

import pytest

from htn.jshop import Planner, load_domain, load_problem

from conftest import ROOT

DOMAIN = str(ROOT / "domains" / "kitchen.jshop")


def first_plan(problem: str):
    dom = load_domain(DOMAIN)
    prob = load_problem(str(ROOT / "problems" / f"{problem}.jshop"))
    return next(Planner(dom, prob.instances[0], record_trees=True).plans())


@pytest.mark.parametrize(
    "problem,transports,length",
    [("transport_four", 4, 20), ("tray_three", 3, 15), ("set_table_and_clean_up", 8, 43)],
)
def test_transports_decompose_into_searching_fetching_delivering(problem, transports, length):
    plan = first_plan(problem)
    assert len(plan.steps) == length
    tops = plan.tree.children
    assert [t.name for t in tops] == ["transporting"] * transports
    for k, t in enumerate(tops, 1):
        assert t.path == f"transporting :call {k}"
        assert [c.name for c in t.children] == ["searching", "fetching", "delivering"]
        assert t.find(f"transporting :call {k}/delivering").path.endswith("/delivering")
    # the general plan carries one object at a time
    holding = 0
    for s in plan.steps:
        holding += s.name.startswith("!grasp") - (s.name == "!place")
        assert holding <= 1


def test_drawer_is_opened_and_closed_for_each_spoon():
    lines = first_plan("set_table_and_clean_up").lines()
    assert lines.count("(!open drawer)") == 2 and lines.count("(!close drawer)") == 2
    assert lines.index("(!grasp-from spoon1 drawer left)") == lines.index("(!open drawer)") + 1
