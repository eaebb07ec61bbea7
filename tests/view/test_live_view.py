"""The live view of ``htn run``: the behaviour tree around the running action,
which stays on screen with all its ancestors whatever the terminal height."""

from __future__ import annotations

import re

import pytest

from htn.cli.tree_view import behaviour_rows, fit, render_rows
from htn.executor.dispatcher import TaskDispatcher
from htn.executor.log import EventLog
from htn.jshop import Planner, load_domain, load_problem
from htn.robot.backends import RobotRequest, make_robot

from conftest import ROOT


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
        assert len(shown) == min(height, len(rows))  # the screen is used, never overrun
        texts = [r.text for r, _ in shown]
        assert ctx.text in texts
        # its node path, level by level: transporting :call 7, .../fetching, ...
        path = ctx.node.path.split("/")
        ancestors = ["plan"] + ["/".join(path[:k]) for k in range(1, len(path))]
        must = (
            ancestors
            + [ctx.text]
            + (["execute | hold: " + ", ".join(ctx.holds)] if ctx.holds else [])
        )
        assert [t for t in texts if t in must] == must[-height:]
        seen.append(rec["step"])
        render_rows(shown)  # renders without error

    log.listeners.append(on_event)
    assert dispatcher.run().result == "verified"
    assert seen == list(range(1, 44))


def test_the_terminal_view_keeps_a_log_above_the_tree_and_counts_follow_repairs(tmp_path):
    # the coffee robot, seed 4: a fault, a retry, then a repair that re-plans
    # a task with a verified step in it; the summary counts 4 steps, the tree
    # holds 3 (the verified one was grafted out)
    import io

    from rich.console import Console

    from htn.cli.tree_view import LiveTreeView
    from htn.executor.config import load_retries
    from htn.executor.dispatcher import actions

    from coffee import COFFEE, MORNING

    (tmp_path / "coffee.jshop").write_text(COFFEE)
    (tmp_path / "morning.jshop").write_text(MORNING)
    dom = load_domain(str(tmp_path / "coffee.jshop"))
    inst = load_problem(str(tmp_path / "morning.jshop")).instances[0]
    plan = next(Planner(dom, inst, record_trees=True).plans())
    robot = make_robot("symbolic", RobotRequest(dom, inst, "effect=0.3", 4))
    log = EventLog(None, clock=lambda: robot.sim_time)
    dispatcher = TaskDispatcher(
        robot,
        dom,
        inst,
        plan.steps,
        load_retries(str(tmp_path / "coffee.jshop"), dom.operators),
        log,
        tree=plan.tree,
        replan=True,
    )
    screen = io.StringIO()
    view = LiveTreeView(
        lambda: dispatcher,
        Console(file=screen, force_terminal=True, color_system=None, width=160, height=40),
    )
    log.listeners.append(view.event)
    with view:
        summary = dispatcher.run()
    assert summary.result == "verified" and summary.replans >= 1
    assert len(list(actions(dispatcher.root))) < summary.steps  # the case of issue 19
    # what the terminal got, without the cursor movements of the redraws
    out = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]|\r", "\n", screen.getvalue())
    # the log: every outcome, the fault, the repair, each once, in order
    kept = [
        line.split()[1]
        for line in out.splitlines()
        if len(line.split()) > 1 and line.split()[1] in ("fault", "replanned", "verified")
    ]
    assert kept.count("replanned") == summary.replans and "fault" in kept
    assert kept.count("verified") == summary.verified
    # the tree drawn last counts what the summary counts, the only top-level
    # task (serve) too
    last = out[out.rindex("sim ") :]
    counts = f"{summary.verified}/{summary.steps} steps"
    assert f"plan  {counts}" in last and f"serve  {counts}" in last, last
