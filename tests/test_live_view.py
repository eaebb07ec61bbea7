"""The live view of ``htn run``: the behaviour tree around the running action,
which stays on screen with all its ancestors whatever the terminal height."""
from __future__ import annotations

import pytest

from conftest import ROOT
from htn.cli.tree_view import behaviour_rows, fit, render_rows
from htn.executor.dispatcher import TaskDispatcher
from htn.executor.log import EventLog
from htn.jshop import Planner, load_domain, load_problem
from htn.robot.backends import RobotRequest, make_robot


@pytest.mark.parametrize("height", [40, 12, 5])
def test_the_running_action_and_its_ancestors_are_always_shown(height):
    dom = load_domain(str(ROOT / "domains" / "kitchen.jshop"))
    inst = load_problem(str(ROOT / "problems" / "set_table_and_clean_up.jshop")).instances[0]
    plan = next(Planner(dom, inst, record_trees=True).plans())
    robot = make_robot("symbolic", RobotRequest(dom, inst))
    log = EventLog(None, clock=lambda: robot.sim_time)
    dispatcher = TaskDispatcher(robot, dom, inst, plan.steps, {}, log, tree=plan.tree)
    seen = []

    def on_event(rec):
        if rec["event"] != "start":
            return
        ctx = dispatcher.running
        rows = behaviour_rows(dispatcher.root, ctx, None, {})
        shown = fit(rows, height)
        assert len(shown) == min(height, len(rows))     # the screen is used, never overrun
        texts = [r.text for r, _ in shown]
        assert ctx.text in texts
        # its node path, level by level: transporting :call 7, .../fetching, ...
        path = ctx.node.path.split("/")
        ancestors = ["plan"] + ["/".join(path[:k]) for k in range(1, len(path))]
        must = ancestors + [ctx.text] + (["execute | hold: " + ", ".join(ctx.holds)]
                                         if ctx.holds else [])
        assert [t for t in texts if t in must] == must[-height:]
        seen.append(rec["step"])
        render_rows(shown)          # renders without error

    log.listeners.append(on_event)
    assert dispatcher.run().result == "verified"
    assert seen == list(range(1, 44))
