"""The kitchen in PyBullet (headless, DIRECT): two arms, a drawer, a tray.

The acceptance point of the plan-transformations issue: the transformed
set_table_and_clean_up plan runs verified in the simulation. Beyond that, the
world the simulation ends in must be the one the plan predicts, and the
monitors must notice when an action's effect did not happen.
"""

from __future__ import annotations

import json
import math

import pytest

from htn.executor.config import load_retries
from htn.executor.dispatcher import TaskDispatcher
from htn.executor.log import EventLog
from htn.executor.outcome import Outcome
from htn.executor.repair import observed_instance
from htn.jshop import Planner, load_domain, load_problem
from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.plans.plan import Step
from htn.jshop.readers.jshop2 import parse_step
from htn.jshop.readers.load import parse_text
from htn.robot.kitchen_sim import KitchenRobot
from htn.robot.pybullet_sim import Faults
from htn.robot.world import ROBOT_HALF_WIDTH, _rect_seg_dist, _table_rect, kitchen_world_from_state
from htn.transform import rules
from htn.transform.framework import Framework, Workspace

from conftest import ROOT, run_htn

pytestmark = pytest.mark.sim

DOMAIN = str(ROOT / "domains" / "kitchen.jshop")


def instance(problem: str):
    return load_problem(str(ROOT / "problems" / f"{problem}.jshop")).instances[0]


def transformed_plan(problem: str):
    fw = Framework()
    rules.register(fw)
    ws = fw.apply_all_transformations(
        Workspace.from_problem(load_domain(DOMAIN), instance(problem))
    )
    return ws


def execute(problem: str, steps, faults: str = "", seed: int = 0):
    dom = load_domain(DOMAIN)
    inst = instance(problem)
    robot = KitchenRobot(
        kitchen_world_from_state(inst.state), faults=Faults.parse(faults), seed=seed
    )
    log = EventLog(None, clock=lambda: robot.sim_time)
    summary = TaskDispatcher(robot, dom, inst, steps, load_retries(DOMAIN), log).run()
    return summary, log.events, robot


def predicted_facts(problem: str, steps) -> set:
    """The dynamic facts the plan says hold at its end."""
    dom = load_domain(DOMAIN)
    checker = Planner(dom, S.ProblemInstance(instance(problem).state, S.TaskList([])))
    for s in steps:
        assert checker.apply_step(s.name, s.args), s
    dynamic = dom.dynamic_predicates() - {"found"}  # what was seen is not observable later
    return {(p, tuple(a)) for p, a in checker.state.facts() if p in dynamic}


@pytest.mark.slow
def test_transformed_set_table_and_clean_up_runs_verified_in_pybullet(tmp_path):
    plan, log = tmp_path / "t.txt", tmp_path / "run.jsonl"
    r = run_htn("transform", DOMAIN, ROOT / "problems" / "set_table_and_clean_up.jshop", "-o", plan)
    assert r.returncode == 0, r.stderr
    text = plan.read_text()
    for step in ("(!lift-tray tray1)", "(!grasp bowl2 sink_area right)", "(!close drawer)"):
        assert step in text  # tray, both-hands and container rewrites are in the plan
    assert (
        text.splitlines().count("(!open drawer)") == 1
    )  # a step line (the ; tasks: note has it too)
    assert text.count("(!look-for tray1 kitchen_island)") == 5  # before each load and the lift
    r = run_htn("run", plan, "--sim", "--log", log)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stdout.splitlines()[-1].startswith("verified: 48 of 48 steps verified")
    events = [json.loads(line) for line in log.read_text().splitlines()]
    done = [e for e in events if e["event"] in ("verified", "aborted", "failed")]
    assert [e["event"] for e in done] == ["verified"] * 48


@pytest.mark.slow
@pytest.mark.parametrize("which", ["original", "transformed"])
def test_the_simulated_kitchen_ends_as_the_plan_predicts(which):
    ws = transformed_plan("set_table_and_clean_up")
    steps = (
        next(Planner(load_domain(DOMAIN), instance("set_table_and_clean_up")).plans()).steps
        if which == "original"
        else ws.plan.steps
    )
    summary, events, robot = execute("set_table_and_clean_up", steps)
    try:
        assert summary.result == "verified" and summary.retries == 0
        observed = {(p, tuple(a)) for p, a in robot.observe()}
        assert observed == predicted_facts("set_table_and_clean_up", steps)
        # the four objects really stand on the sink area's table, upright
        for obj in ("bowl1", "bowl2", "spoon1", "spoon2"):
            assert robot.check_on(obj, "sink_area").ok
            ph = robot.physics
            _, orn = ph.p.getBasePositionAndOrientation(ph.body_of[obj], physicsClientId=ph.cid)
            assert abs(ph.p.getEulerFromQuaternion(orn)[0]) < 0.2
    finally:
        robot.close()


@pytest.mark.slow
@pytest.mark.parametrize("problem", ["transport_four", "tray_three"])
def test_other_kitchen_problems_run_verified_with_and_without_transformation(problem):
    ws = transformed_plan(problem)
    original = next(Planner(load_domain(DOMAIN), instance(problem)).plans()).steps
    for steps in (original, ws.plan.steps):
        summary, _, robot = execute(problem, steps)
        try:
            assert summary.result == "verified", summary
            observed = {(p, tuple(a)) for p, a in robot.observe()}
            assert observed == predicted_facts(problem, steps)
        finally:
            robot.close()


def run_steps(robot, problem, lines):
    """Execute plan steps with the task dispatcher, one attempt each, from the
    world as ``robot`` observes it now; their outcomes (up to the first one
    not verified, where the dispatcher stops)."""
    dom = load_domain(DOMAIN)
    steps = [Step(a.name, a.args) for a in (parse_step(line, "<test>", 1) for line in lines)]
    log = EventLog(None, clock=lambda: robot.sim_time)
    TaskDispatcher(
        robot, dom, observed_instance(dom, instance(problem), robot), steps, {}, log
    ).run()
    return [
        Outcome(e["event"]) for e in log.events if e["event"] in ("verified", "failed", "aborted")
    ]


@pytest.mark.slow
def test_a_closed_drawer_hides_its_spoons_and_the_grasp_is_aborted():
    inst = instance("set_table_and_clean_up")
    robot = KitchenRobot(kitchen_world_from_state(inst.state))
    try:
        got = run_steps(
            robot,
            "set_table_and_clean_up",
            [
                "(!navigate start sink_area)",
                "(!look-for spoon1 sink_area)",
                "(!grasp-from spoon1 drawer left)",
            ],
        )
        # seen to be in the drawer, but not graspable through its housing
        assert got == [Outcome.VERIFIED, Outcome.VERIFIED, Outcome.ABORTED]
        assert robot.check_opened("drawer", False).ok
        got = run_steps(
            robot,
            "set_table_and_clean_up",
            ["(!open drawer)", "(!grasp-from spoon1 drawer left)", "(!close drawer)"],
        )
        assert got == [Outcome.VERIFIED] * 3
        assert robot.arms.hands == {"left": "spoon1", "right": None}
        # the other spoon moved with the drawer and back
        assert robot.drawers.holds("spoon2", robot.drawers["drawer"])
    finally:
        robot.close()


@pytest.mark.slow
def test_tray_needs_both_hands_and_carries_what_stands_on_it():
    inst = instance("tray_three")
    robot = KitchenRobot(kitchen_world_from_state(inst.state))
    try:
        got = run_steps(
            robot,
            "tray_three",
            [
                "(!navigate start kitchen_island)",
                "(!look-for cup kitchen_island)",
                "(!grasp cup kitchen_island left)",
            ],
        )
        assert got == [Outcome.VERIFIED] * 3
        # one hand holds the cup: lifting the tray fails, nothing moves
        assert run_steps(robot, "tray_three", ["(!lift-tray tray1)"]) == [Outcome.FAILED]
        got = run_steps(
            robot,
            "tray_three",
            [
                "(!put-on-tray cup tray1 left)",
                "(!lift-tray tray1)",
                "(!navigate kitchen_island sink_area)",
                "(!lower-tray tray1 sink_area)",
            ],
        )
        assert got == [Outcome.VERIFIED] * 4
        assert robot.check_on_tray("cup", "tray1").ok
        assert robot.check_tray_carried("tray1", False, "sink_area").ok
        assert not robot.check_tray_carried("tray1", False, "kitchen_island").ok
    finally:
        robot.close()


@pytest.mark.slow
def test_faults_are_recovered_by_retries():
    # (a slip while driving is not: see test_monitoring.py)
    steps = transformed_plan("set_table_and_clean_up").plan.steps
    summary, events, robot = execute(
        "set_table_and_clean_up", steps, faults="detect=0.2,nav=0.1", seed=3
    )
    try:
        assert robot.injected, "the seed injects faults"
        assert summary.result == "verified" and summary.retries >= len(robot.injected) > 0
    finally:
        robot.close()


def test_replanning_from_where_a_navigation_stopped():
    dom = load_domain(DOMAIN)
    inst = instance("transport_four")
    robot = KitchenRobot(kitchen_world_from_state(inst.state), faults=Faults.parse("nav=1"))
    try:
        assert run_steps(robot, "transport_four", ["(!navigate start kitchen_island)"]) == [
            Outcome.ABORTED
        ]
        observed = observed_instance(dom, inst, robot)
        here = [a for a in observed.state if a.pred == "area" and a.args[0] == "here"]
        assert len(here) == 1 and ("robot-at", ("here",)) in robot.observe()
        x, y = here[0].args[1:]
        assert 0.0 < math.dist((x, y), (-2.5, -2.0)) < math.dist((0.0, 1.5), (-2.5, -2.0))
        plan = next(Planner(dom, observed).plans())
        assert str(plan.steps[0]) == "(!navigate here kitchen_island)"
        assert len(plan.steps) == 20
    finally:
        robot.close()


@pytest.mark.parametrize("problem", ["set_table_and_clean_up", "transport_four", "tray_three"])
def test_tables_keep_clear_of_every_drive(problem):
    w = kitchen_world_from_state(instance(problem).state)
    areas = [(p.x, p.y) for p in w.places.values()]
    for name, f in w.furniture.items():
        pl = w.places[name]
        heading = math.atan2(f.y - pl.y, f.x - pl.x)  # the area's pose faces its table
        assert abs((heading - pl.theta + math.pi) % (2 * math.pi) - math.pi) < 1e-9
        rect = _table_rect(pl.x, pl.y, pl.theta)
        for i, a in enumerate(areas):
            for b in areas[i + 1 :]:
                assert _rect_seg_dist(rect, a, b) >= ROBOT_HALF_WIDTH


def test_areas_too_close_for_tables_are_a_clear_error(tmp_path):
    text = """(defproblem cramped kitchen
  ((area a 0.0 0.0) (area b 1.0 0.0) (area c -1.0 0.0) (area d 0.0 1.0)
   (area start 0.0 -1.0) (at cup a) (robot-at start) (free left) (free right))
  ((transporting cup a b)))"""
    inst = parse_text(text, "cramped.jshop").instances[0]
    with pytest.raises(HtnError, match="cannot lay out the simulated kitchen"):
        kitchen_world_from_state(inst.state)
    prob = tmp_path / "cramped.jshop"
    prob.write_text(text)
    plan = tmp_path / "plan.txt"
    assert run_htn("plan", DOMAIN, prob, "-o", plan).returncode == 0
    r = run_htn("run", plan, "--sim")
    assert r.returncode == 2
    first = r.stderr.splitlines()[0]
    assert first.startswith(
        f"{prob}:2:4: cannot lay out the simulated kitchen: the table of area 'a'"
    ), r.stderr
    assert "Traceback" not in r.stderr


def test_an_object_nowhere_is_a_clear_error(tmp_path):
    prob = tmp_path / "nowhere.jshop"
    prob.write_text("""(defproblem nowhere kitchen
  ((area a 0.0 0.0) (area start 3.0 0.0)
   (at cup nowhere) (robot-at start) (free left) (free right))
  ((transporting cup a start)))""")
    plan = tmp_path / "plan.txt"
    plan.write_text("Plan cost: 1.0\n\n(!navigate start a)\n--------------------\n")
    r = run_htn("run", plan, "--sim", "--domain", DOMAIN, "--problem", prob)
    assert r.returncode == 2
    assert r.stderr.splitlines()[0] == (
        f"{prob}:3:4: cup is at 'nowhere', which is neither an area nor a container"
    )
