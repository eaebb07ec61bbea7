"""The world model a long-lived planner keeps (htn.api.world): facts from
the problem, checked updates, goals planned from what is believed now."""

from __future__ import annotations

import pytest

import htn
from htn.api.world import WorldModel, plan_goal
from htn.jshop.language.errors import HtnError

from conftest import ROOT

DOMAIN = ROOT / "domains" / "domestic.jshop"
PROBLEM = ROOT / "problems" / "bring_object.jshop"
GOAL = "((bring_object jenny pringles guest))"


@pytest.fixture
def world():
    return WorldModel(DOMAIN, PROBLEM)


def test_it_starts_from_the_problems_state_and_answers_patterns(world):
    assert "(robot_at jenny home_base)" in world.facts()
    assert world.query("(robot_at ?who ?where)") == ["(robot_at jenny home_base)"]
    assert world.query("(location ?l 2.2 ?y ?z)") == [
        "(location counter_front 2.2 1.5 0.0)",
        "(location dining_front 2.2 -1.5 0.0)",
    ]
    assert world.query("(robot_at ?x ?x)") == []  # the same variable, the same thing


def test_a_goal_planned_from_the_model_is_the_problem_files_plan(world):
    stream = plan_goal(world, GOAL)
    from_model = next(iter(stream))
    stream.close()
    from_file = next(iter(htn.plan(DOMAIN, PROBLEM)))
    assert from_model.lines() == from_file.lines()


def test_facts_change_the_next_plan(world):
    before = next(iter(plan_goal(world, GOAL))).lines()
    where = world.query("(robot_at jenny ?where)")[0]
    world.update(add=["(robot_at jenny dining_front)"], delete=[where])
    after = next(iter(plan_goal(world, GOAL))).lines()
    assert before != after
    assert world.query("(robot_at jenny ?w)") == ["(robot_at jenny dining_front)"]


@pytest.mark.parametrize(
    "tasks, message",
    [
        ("((fly_to jenny moon))", "goal:1:3: unknown task 'fly_to'"),
        ("((bring_object jenny pringles))", "goal:1:3: 'bring_object' takes 3 arguments, given 2"),
        ("((bring_object jenny pringles guest)", "goal:1:1: this '(' is never closed"),
        ("(bring_object jenny pringles guest)", "goal:1:2: the task list is a list of tasks"),
        ("  ", "goal:1:1: the goal has no tasks"),
    ],
)
def test_a_bad_goal_is_a_located_error(world, tasks, message):
    with pytest.raises(HtnError) as caught:
        world.problem(tasks)
    assert str(caught.value).startswith(message)


@pytest.mark.parametrize(
    "fact, message",
    [
        ("(flies jenny)", "facts:1:1: unknown predicate 'flies'"),
        ("(robot_at jenny)", "facts:1:1: 'robot_at' has 2 argument(s) in the domain, given 1"),
        ("(robot_at ?x kitchen)", "facts:1:1: atoms in the initial state must be ground"),
        ("(robot_at jenny", "facts:1:1: this '(' is never closed"),
        ("(free_hand jenny) x)", "facts:1:20: this ')' closes nothing"),
    ],
)
def test_a_bad_fact_is_a_located_error_and_changes_nothing(world, fact, message):
    before = world.facts()
    with pytest.raises(HtnError) as caught:
        world.update(add=["(robot_at jenny kitchen)", fact], source="facts")
    assert str(caught.value).startswith(message)
    assert world.facts() == before


def test_what_a_run_verified_becomes_the_model(world):
    from htn.api.run import prepare

    plan = next(iter(plan_goal(world, GOAL)))
    with prepare(
        plan, robot="symbolic", domain=world.domain, problem=world.problem(GOAL)
    ) as execution:
        assert sorted(execution.believed()) == sorted((a.pred, a.args) for a in world.atoms())
        execution.begin()
        assert execution.execute().summary.result == "verified"
        world.believe(execution.believed())
    assert "(has guest pringles)" in world.facts()
    assert "(has guest pringles)" not in WorldModel(DOMAIN, PROBLEM).facts()
    # the next goal is planned from there: the pringles are no longer on
    # the counter to bring, so the same goal has no plan now
    assert list(plan_goal(world, GOAL)) == []


def test_an_hddl_domain_is_refused_with_the_reason():
    hddl = next((ROOT.parent / "shared" / "corpus" / "ipc2020-to").glob("*/domain.hddl"), None)
    if hddl is None:
        pytest.skip("the shared corpus is not beside the checkout")
    with pytest.raises(HtnError, match="JSHOP2 domains only"):
        WorldModel(hddl)


def test_facts_reported_while_a_goal_runs_outlive_the_runs_belief():
    """What other programs report while a goal runs is applied again on top
    of what the run verified, not overwritten by it."""
    from htn.api.agent import Agent

    agent = Agent(DOMAIN, PROBLEM)
    seen = []

    def on_event(rec):
        if rec["event"] == "start" and not seen:
            seen.append(
                agent.world.update(
                    ["(object_on coke kitchen_counter)"],
                    ["(object_on pringles kitchen_counter)"],
                    "camera",
                )
            )

    result = agent.execute("((inform jenny hello))", on_event=on_event)
    assert result.outcome == "verified" and seen
    facts = agent.world.query("(object_on ?o ?f)")
    assert "(object_on coke kitchen_counter)" in facts
    assert "(object_on pringles kitchen_counter)" not in facts
