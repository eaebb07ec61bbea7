"""A planner and executor that lives across goals (htn.api.agent): goals
planned from the world model, preempted at the current action, refused
with the located reason."""
from __future__ import annotations

import threading

from htn.api.agent import Agent

from conftest import ROOT

DOMAIN = ROOT / "domains" / "domestic.jshop"
PROBLEM = ROOT / "problems" / "bring_object.jshop"
GOAL = "((bring_object jenny pringles guest))"


def agent() -> Agent:
    return Agent(DOMAIN, PROBLEM, robot="symbolic")


def test_a_goal_runs_as_htn_run_would_and_its_effects_stay():
    a = agent()
    r = a.execute(GOAL)
    assert r.outcome == "verified" and r.verified == r.steps == 8
    assert r.summary.startswith("verified: 8 of 8 steps verified")
    assert [e["event"] for e in r.log][:2] == ["header", "tree"]
    assert "(has guest pringles)" in a.world.facts()


def test_a_bad_goal_is_refused_with_the_located_reason_and_nothing_moves():
    a = agent()
    before = a.world.facts()
    for tasks, error in (("((fly_to jenny moon))", "goal:1:3: unknown task 'fly_to'"),
                         ("((bring_object jenny))", "goal:1:3: 'bring_object' takes 3"),
                         ("((bring_object jenny pringles guest)", "goal:1:1: this '('")):
        r = a.execute(tasks)
        assert r.outcome == "refused" and r.error.startswith(error), r.error
        assert r.log == []
    assert a.world.facts() == before
    assert a.execute(GOAL).outcome == "verified"       # it lives on


def test_preempted_at_the_current_action_and_the_same_goal_goes_on_from_there():
    a = agent()

    def preempt_after_step_3(rec):
        if rec["event"] == "verified" and rec["step"] == 3:
            cancel = threading.Thread(target=a.preempt)     # as a cancel comes: another thread
            cancel.start()
            cancel.join()

    r = a.execute(GOAL, on_event=preempt_after_step_3)
    assert r.outcome == "preempted" and r.verified == 3, r.summary
    assert r.summary.startswith("preempted: 3 of 8 steps verified")
    assert r.log[-2]["event"] == "interrupted" and "preempted" in r.log[-2]["detail"]
    # what was verified stays: the robot is at the counter, the goal is planned from there
    assert a.world.query("(robot_at jenny ?where)") == ["(robot_at jenny counter_front)"]
    again = a.execute(GOAL)
    assert again.outcome == "verified" and again.steps == 7
    assert not any(s.startswith("(!move_base jenny home_base") for s in again.plan)


def test_a_reported_fact_changes_the_next_plan():
    a = agent()
    first = a.plan(GOAL)
    a.world.update(delete=a.world.query("(robot_at jenny ?w)"),
                   add=["(robot_at jenny counter_front)"], source="camera")
    second = a.plan(GOAL)
    assert len(second.steps) == len(first.steps) - 1


def test_preempt_with_no_goal_running_says_so():
    assert agent().preempt() is False
