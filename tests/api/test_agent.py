"""A planner and executor that lives across goals (htn.api.agent): goals
planned from the world model, preempted at the current action (the log
says so), resumed after the goal that preempted them, a running action
going on into the newer goal's run, refused with the located reason."""

from __future__ import annotations

import json
import threading

from htn.api.agent import Agent

from conftest import ROOT

DOMAIN = ROOT / "domains" / "domestic.jshop"
PROBLEM = ROOT / "problems" / "bring_object.jshop"
GOAL = "((bring_object jenny pringles guest))"


def agent() -> Agent:
    return Agent(DOMAIN, PROBLEM, robot="symbolic")


def preempting(a: Agent, event: str, step: int, **preempt):
    """An ``on_event`` that preempts ``a`` from another thread (as a cancel
    or a newer goal comes) when step ``step`` logs ``event``."""

    def on_event(rec):
        if rec["event"] == event and rec["step"] == step:
            other = threading.Thread(target=a.preempt, kwargs=preempt)
            other.start()
            other.join()

    return on_event


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
    for tasks, error in (
        ("((fly_to jenny moon))", "goal:1:3: unknown task 'fly_to'"),
        ("((bring_object jenny))", "goal:1:3: 'bring_object' takes 3"),
        ("((bring_object jenny pringles guest)", "goal:1:1: this '('"),
    ):
        r = a.execute(tasks)
        assert r.outcome == "refused" and r.error.startswith(error), r.error
        assert r.log == []
    assert a.world.facts() == before
    assert a.execute(GOAL).outcome == "verified"  # it lives on


def test_preempted_at_the_current_action_and_the_same_goal_goes_on_from_there():
    a = agent()

    def preempt_after_step_3(rec):
        if rec["event"] == "verified" and rec["step"] == 3:
            cancel = threading.Thread(target=a.preempt)  # as a cancel comes: another thread
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
    a.world.update(
        delete=a.world.query("(robot_at jenny ?w)"),
        add=["(robot_at jenny counter_front)"],
        source="camera",
    )
    second = a.plan(GOAL)
    assert len(second.steps) == len(first.steps) - 1


def test_preempt_with_no_goal_running_says_so():
    assert agent().preempt() is False


def test_the_log_of_a_preempted_goal_says_preempted_and_why(tmp_path):
    a = agent()
    r = a.execute(
        GOAL,
        log=tmp_path / "goal.jsonl",
        on_event=preempting(a, "verified", 3, why="preempted by a newer goal"),
    )
    log = [json.loads(line) for line in (tmp_path / "goal.jsonl").read_text().splitlines()]
    assert log == r.log
    assert log[-2]["event"] == "interrupted"
    assert log[-2]["detail"] == "preempted by a newer goal; the robot holds its pose"
    summary = log[-1]
    assert summary["event"] == "summary" and summary["result"] == summary["detail"] == "preempted"
    assert summary["reason"] == "preempted by a newer goal" and summary["verified"] == 3
    assert r.summary == "preempted: 3 of 8 steps verified, 0 retries, 0 replans, 3.0 s simulated"
    assert r.remaining == "((bring_object jenny pringles guest))"
    # a goal that ends otherwise has no reason in its summary
    assert "reason" not in a.execute("((bring_object jenny coke guest))").log[-1]


def test_a_goal_preempted_while_it_is_planned_ends_before_its_first_step():
    a = agent()
    plan = a._first_plan

    def planning(*args):  # a cancel comes (another thread) while the goal is planned
        other = threading.Thread(target=a.preempt, args=("cancelled by the client",))
        other.start()
        other.join()
        return plan(*args)

    a._first_plan = planning
    r = a.execute(GOAL)
    assert r.outcome == "preempted" and r.verified == 0 and r.remaining == GOAL
    assert r.log[-2]["detail"] == "cancelled by the client before the first step"
    a._first_plan = plan
    assert a.preempt() is False  # between goals: nothing to preempt, nothing kept
    assert a.execute(GOAL).outcome == "verified"


def test_a_preempted_goal_resumes_after_the_newer_one_and_both_end_verified(tmp_path):
    a = agent()
    first = a.execute(GOAL, on_event=preempting(a, "verified", 3))
    assert first.outcome == "preempted" and first.verified == 3
    newer = a.execute("((bring_object jenny coke guest))")
    assert newer.outcome == "verified", newer.summary
    resumed = a.resume(first, log=tmp_path / "resumed.jsonl")
    assert resumed.outcome == "verified", resumed.summary
    # re-planned from the world model: from the sofa, where the coke was handed over
    assert resumed.plan[:3] == first.done
    assert resumed.plan[3:5] == [
        "(!say jenny task_accepted)",
        "(!move_base jenny sofa_front counter_front)",
    ]
    assert resumed.verified == resumed.steps == 3 + 8 and resumed.resumed == 1
    assert resumed.summary == (
        "verified: 11 of 11 steps verified, 0 retries, 0 replans, "
        "19.0 s simulated; resumed after a preemption, 3 steps "
        "verified before"
    )
    summary = json.loads((tmp_path / "resumed.jsonl").read_text().splitlines()[-1])
    assert summary["result"] == "verified" and summary["verified"] == 8
    assert summary["resumed"] == {
        "tasks": "((bring_object jenny pringles guest))",
        "times": 1,
        "verified_before": 3,
        "goal": GOAL,
    }
    assert a.world.query("(has guest ?what)") == ["(has guest coke)", "(has guest pringles)"]


def test_a_goal_with_tasks_done_resumes_only_the_tasks_left():
    a = agent()
    two = "((bring_object jenny pringles guest) (bring_object jenny coke guest))"
    first = a.execute(two, on_event=preempting(a, "verified", 9))  # the coke's first step
    assert first.outcome == "preempted" and first.verified == 9
    assert first.remaining == "((bring_object jenny coke guest))"  # the pringles are done
    resumed = a.resume(first)
    # the coke's task is planned whole again (its first step, a say, too)
    assert resumed.outcome == "verified" and resumed.verified == resumed.steps == 9 + 8
    assert resumed.tasks == two


def test_a_task_the_domain_cannot_resume_from_its_state_is_refused_saying_so():
    a = agent()
    first = a.execute(GOAL, on_event=preempting(a, "verified", 4))  # the pringles grasped
    assert first.done[-1] == "(!grasp jenny pringles kitchen_counter)"
    r = a.resume(first)
    assert r.outcome == "refused" and r.verified == 4 and r.plan == first.done
    assert r.error == (
        "goal: resuming ((bring_object jenny pringles guest)): no plan reaches "
        "these tasks from the current state"
    )
    assert r.summary.startswith("refused: resuming ((bring_object jenny pringles guest))")


def test_the_running_action_goes_on_when_the_newer_goal_starts_with_it():
    a = agent()
    drive = "((go_to jenny counter_front))"  # (!move_base jenny home_base counter_front)
    first = a.execute(GOAL, on_event=preempting(a, "start", 2, next_goal=drive))
    # the drive went on to its end, then the goal halted before its next action
    assert first.outcome == "preempted" and first.verified == 2, first.summary
    assert [e["event"] for e in first.log if e["step"] == 2] == [
        "start",
        "feedback",
        "finished",
        "verified",
    ]
    assert first.log[-2]["event"] == "interrupted" and first.log[-2]["step"] is None
    newer = a.execute(drive)
    assert newer.outcome == "verified" and newer.plan == [
        "(!move_base jenny home_base counter_front)"
    ]
    adopted = [e for e in newer.log if e["event"] == "verified"]
    assert len(adopted) == 1 and adopted[0]["adopted"] and adopted[0]["step"] == 1
    assert not any(e["event"] == "start" for e in newer.log)  # not started again
    assert a.robot.sim_time == 2.0
    assert a.resume(first).outcome == "verified"


def test_a_newer_goal_that_does_not_start_with_the_running_action_is_planned_afresh():
    a = agent()
    first = a.execute(
        GOAL, on_event=preempting(a, "start", 2, next_goal="((go_to jenny sofa_front))")
    )
    # (the symbolic robot's action ends within the tick it starts in)
    assert first.outcome == "preempted" and first.verified == 2
    newer = a.execute("((go_to jenny sofa_front))")
    assert newer.plan == ["(!move_base jenny counter_front sofa_front)"]
    assert not any(e.get("adopted") for e in newer.log)
