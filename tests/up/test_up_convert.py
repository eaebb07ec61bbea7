"""The in-memory conversion of UP problems and the hierarchical plan validator."""

from __future__ import annotations

import pytest

pytest.importorskip("unified_planning")

from test_up_cases import cases  # noqa: E402
from unified_planning.engines import PlanGenerationResultStatus as Status  # noqa: E402
from unified_planning.engines.plan_validator import SequentialPlanValidator  # noqa: E402
from unified_planning.engines.results import FailedValidationReason  # noqa: E402
from unified_planning.model.htn import HierarchicalProblem, Method  # noqa: E402
from unified_planning.plans import ActionInstance, SequentialPlan  # noqa: E402
from unified_planning.plans.hierarchical_plan import Decomposition, HierarchicalPlan, MethodInstance  # noqa: E402
from unified_planning.shortcuts import (  # noqa: E402
    And,
    BoolType,
    Equals,
    Exists,
    Forall,
    Implies,
    InstantaneousAction,
    Not,
    OneshotPlanner,
    PlanValidator,
    UserType,
    Variable,
    get_environment,
)

import htn.up  # noqa: E402,F401

from conftest import SHARED  # noqa: E402

get_environment().credits_stream = None
IPC = SHARED / "corpus" / "ipc2020-to"


def validate(problem, plan):
    with PlanValidator(name="htn") as v:
        return v.validate(problem, plan)


def up_valid(problem, plan) -> bool:
    v = SequentialPlanValidator()
    v.skip_checks = True
    return v.validate(problem, plan.action_plan).status.name == "VALID"


# ---------------------------------------------------------------- features


def delivery():
    """A robot with an object fluent (its place), a package carried by a
    conditional effect, a forall effect, exists/forall/implies conditions
    and a goal."""
    pb = HierarchicalProblem("delivery")
    Place, Thing = UserType("Place"), UserType("Thing")
    here, there, far = (pb.add_object(n, Place) for n in ("here", "there", "far"))
    box, ball = pb.add_object("box", Thing), pb.add_object("ball", Thing)
    robot_at = pb.add_fluent("robot_at", Place)  # an object fluent
    thing_at = pb.add_fluent("thing_at", BoolType(), t=Thing, p=Place, default_initial_value=False)
    held = pb.add_fluent("held", BoolType(), t=Thing, default_initial_value=False)
    link = pb.add_fluent("link", BoolType(), a=Place, b=Place, default_initial_value=False)
    seen = pb.add_fluent("seen", BoolType(), p=Place, default_initial_value=False)
    pb.set_initial_value(robot_at, here)
    pb.set_initial_value(thing_at(box, here), True)
    pb.set_initial_value(thing_at(ball, far), True)
    for a, b in ((here, there), (there, far), (far, here)):
        pb.set_initial_value(link(a, b), True)
    move = InstantaneousAction("move", to=Place)
    t = Variable("t", Thing)
    move.add_precondition(link(robot_at, move.to))  # a fluent as an argument
    move.add_effect(robot_at, move.to)
    move.add_effect(thing_at(t, move.to), True, held(t), forall=[t])  # carried along
    move.add_effect(seen(move.to), True)
    grab = InstantaneousAction("grab", x=Thing)
    grab.add_precondition(thing_at(grab.x, robot_at))
    grab.add_precondition(Forall(Not(held(t)), t))  # one thing at a time
    grab.add_effect(held(grab.x), True)
    drop = InstantaneousAction("drop", x=Thing)
    p = Variable("p", Place)
    drop.add_precondition(held(drop.x))
    drop.add_precondition(Exists(And(Equals(robot_at, p), Implies(seen(p), link(here, p))), p))
    drop.add_effect(held(drop.x), False)
    for a in (move, grab, drop):
        pb.add_action(a)
    deliver = pb.add_task("deliver", x=Thing, to=Place)
    m = Method("m_deliver", x=Thing, src=Place, to=Place)
    m.set_task(deliver, m.x, m.to)
    m.add_precondition(Equals(robot_at, m.src))
    m.add_precondition(thing_at(m.x, m.src))
    s1, s2, s3 = m.add_subtask(grab, m.x), m.add_subtask(move, m.to), m.add_subtask(drop, m.x)
    m.set_ordered(s1, s2, s3)
    pb.add_method(m)
    pb.task_network.add_subtask(deliver, box, there)
    pb.add_goal(thing_at(box, there))
    return pb


def test_object_fluents_conditional_and_forall_effects_and_quantifiers_plan_as_up_means_them():
    problem = delivery()
    with OneshotPlanner(name="htn") as planner:
        assert planner.supports(problem.kind)
        result = planner.solve(problem)
    assert result.status == Status.SOLVED_SATISFICING, result.log_messages
    plan = result.plan
    assert [str(a) for a in plan.action_plan.actions] == ["grab(box)", "move(there)", "drop(box)"]
    (mi,) = plan.decomposition.subtasks.values()
    assert mi.method.name == "m_deliver" and [str(x) for x in mi.parameters] == [
        "box",
        "here",
        "there",
    ]  # src, bound by the precondition only
    assert up_valid(problem, plan)  # UP's own semantics accept the actions
    assert validate(problem, plan).status.name == "VALID"


def test_a_goal_the_decomposition_misses_is_unsolvable():
    problem = delivery()
    problem.add_goal(problem.fluent("seen")(problem.object("far")))
    with OneshotPlanner(name="htn") as planner:
        assert planner.solve(problem).status == Status.UNSOLVABLE_PROVEN


@pytest.mark.skipif(not IPC.is_dir(), reason=f"IPC 2020 sample not found at {IPC}")
@pytest.mark.parametrize(
    "domain", ["Blocksworld-GTOHP", "Childsnack", "Depots", "Rover-GTOHP", "Towers", "Transport"]
)
def test_an_ipc_problem_read_by_up_plans_as_htn_plans_the_hddl_files(domain):
    from unified_planning.io import PDDLReader

    from htn.jshop.readers.load import load_inputs
    from htn.jshop.search.planner import Planner

    dfile = IPC / domain / "domain.hddl"
    pfile = sorted(p for p in (IPC / domain).glob("*.hddl") if p.name != "domain.hddl")[0]
    problem = PDDLReader().parse_problem(str(dfile), str(pfile))
    with OneshotPlanner(name="htn") as planner:
        result = planner.solve(problem, timeout=60)
    assert result.status == Status.SOLVED_SATISFICING
    dom, prob = load_inputs(str(dfile), str(pfile))
    direct = next(Planner(dom, prob.instances[0]).plans(60))
    assert [
        str(a).replace("(", " ").replace(",", "").rstrip(")")
        for a in result.plan.action_plan.actions
    ] == [" ".join([s.name[1:], *s.args]) for s in direct.steps]
    assert up_valid(problem, result.plan)
    assert validate(problem, result.plan).status.name == "VALID"


@pytest.mark.parametrize("search", ["gbfs", "auto"])
def test_a_goal_the_decomposition_misses_is_unsolvable_in_every_search(search):
    problem = delivery()
    problem.add_goal(problem.fluent("seen")(problem.object("far")))
    with OneshotPlanner(name="htn", params={"search": search}) as planner:
        assert planner.solve(problem, timeout=60).status == Status.UNSOLVABLE_PROVEN


HARD = SHARED / "corpus" / "ipc2020-to-hard" / "Multiarm-Blocksworld"


@pytest.mark.slow
@pytest.mark.corpus
@pytest.mark.skipif(not HARD.is_dir(), reason=f"{HARD} not found")
def test_the_heuristic_search_solves_through_up_what_depth_first_cannot():
    """``params={"search": "gbfs"}`` on an instance read by UP's HDDL reader
    where depth-first search in the written order is stuck (a few seconds
    against no plan in 30 s, ``benchmarks/bench_ipc.py``)."""
    from unified_planning.io import PDDLReader

    problem = PDDLReader().parse_problem(str(HARD / "domain.hddl"), str(HARD / "pfile_02_055.hddl"))
    with OneshotPlanner(name="htn", params={"search": "dfs"}) as planner:
        assert planner.solve(problem, timeout=3).status == Status.TIMEOUT
    with OneshotPlanner(name="htn", params={"search": "gbfs"}) as planner:
        result = planner.solve(problem, timeout=120)
    assert result.status == Status.SOLVED_SATISFICING, result.log_messages
    assert up_valid(problem, result.plan)
    assert validate(problem, result.plan).status.name == "VALID"


# ---------------------------------------------------------------- the validator


def htn_go():
    problem = cases()["test:htn-go"].problem
    return problem, cases()["test:htn-go"].valid_plans[0]


def with_actions(plan, actions):
    return HierarchicalPlan(SequentialPlan(actions), plan.decomposition)


def test_an_inapplicable_action_is_named():
    problem, plan = htn_go()
    actions = list(plan.action_plan.actions)
    move = actions[1].action
    actions[1] = ActionInstance(move, (problem.object("l2"), problem.object("l4")))
    res = validate(problem, with_actions(plan, actions))
    assert res.status.name == "INVALID"
    assert res.reason == FailedValidationReason.INAPPLICABLE_ACTION
    assert res.inapplicable_action is actions[1]
    assert "action 2" in res.log_messages[0].message


def test_a_decomposition_that_does_not_give_the_actions_is_invalid():
    problem, plan = htn_go()
    actions = list(plan.action_plan.actions)
    shorter = HierarchicalPlan(SequentialPlan(actions[:-2]), plan.decomposition)
    res = validate(problem, shorter)
    assert res.status.name == "INVALID" and "no more actions" in res.log_messages[0].message


def test_a_method_whose_precondition_fails_is_invalid():
    problem, plan = htn_go()
    go1, go2 = plan.decomposition.subtasks.values()
    noop = problem.method("go-noop")
    l3 = get_environment().expression_manager.ObjectExp(problem.object("l3"))
    wrong = Decomposition(
        {"go_l4": MethodInstance(noop, (l3,), Decomposition({})), "go_final": go2}
    )
    res = validate(problem, HierarchicalPlan(plan.action_plan, wrong))
    assert res.status.name == "INVALID"
    msg = res.log_messages[0].message
    assert "go-noop decomposes go" in msg or "precondition of method go-noop" in msg


def test_a_missing_subtask_and_bad_network_variables_are_invalid():
    problem, plan = htn_go()
    go1, go2 = plan.decomposition.subtasks.values()
    res = validate(problem, HierarchicalPlan(plan.action_plan, Decomposition({"go_l4": go1})))
    assert (
        res.status.name == "INVALID" and "lacks subtask(s) go_final" in res.log_messages[0].message
    )
    # go_final ends at l3: the executable plan breaks final_loc in {l1, l2}
    em = get_environment().expression_manager
    l3, l4 = (em.ObjectExp(problem.object(n)) for n in ("l3", "l4"))
    actions = list(plan.action_plan.actions)[:3]
    back = ActionInstance(actions[0].action, (l4, l3))
    to_l3 = MethodInstance(
        problem.method("go-recursive"),
        (l4, l3, l3),
        Decomposition(
            {
                "move": back,
                "go-rec": MethodInstance(problem.method("go-noop"), (l3,), Decomposition({})),
            }
        ),
    )
    bad = HierarchicalPlan(
        SequentialPlan(actions + [back]), Decomposition({"go_l4": go1, "go_final": to_l3})
    )
    assert up_valid(problem, bad)
    res = validate(problem, bad)
    assert res.status.name == "INVALID"
    assert "final_loc = l3" in res.log_messages[0].message


def test_a_sequential_plan_is_not_validated_by_htn():
    problem, plan = htn_go()
    with PlanValidator(name="htn") as v:
        v.error_on_failed_checks = False
        with pytest.warns(UserWarning):
            res = v.validate(problem, plan.action_plan)
    assert res.status.name == "UNKNOWN"


def test_subtasks_run_in_their_order_not_in_the_order_they_were_added():
    pb = HierarchicalProblem("order")
    first, second = InstantaneousAction("first"), InstantaneousAction("second")
    ready = pb.add_fluent("ready", BoolType(), default_initial_value=False)
    first.add_effect(ready, True)
    second.add_precondition(ready)
    pb.add_action(first)
    pb.add_action(second)
    task = pb.add_task("both")
    m = Method("m_both")
    m.set_task(task)
    s2, s1 = m.add_subtask(second, ident="s2"), m.add_subtask(first, ident="s1")
    m.set_ordered(s1, s2)
    pb.add_method(m)
    pb.task_network.add_subtask(task, ident="root")
    with OneshotPlanner(name="htn") as planner:
        plan = planner.solve(pb).plan
    assert [a.action.name for a in plan.action_plan.actions] == ["first", "second"]
    (mi,) = plan.decomposition.subtasks.values()
    assert {k: v.action.name for k, v in mi.decomposition.subtasks.items()} == {
        "s1": "first",
        "s2": "second",
    }
    assert validate(pb, plan).status.name == "VALID"
