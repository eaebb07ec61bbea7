"""The PyBullet robots are made of parts they hold (issue 35, item 2): no
class of ``robot/`` mixes more than two bases into one ``self``, each part is
an object handed what it needs, and the grasp's preamble exists once."""

from __future__ import annotations

import ast

import pytest

from conftest import ROOT

ROBOT = ROOT / "robot"


def test_no_class_in_robot_has_more_than_two_bases():
    for path in sorted(ROBOT.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ClassDef):
                assert len(node.bases) <= 2, f"{path.name}: class {node.name}"


def test_the_grasp_preamble_is_written_once():
    texts = [path.read_text() for path in ROBOT.glob("*.py")]
    assert sum(t.count(".moved_once(") for t in texts) == 1
    assert sum(t.count("def _grasp_target(") for t in texts) == 1


def _instance(problem: str):
    from htn.jshop import load_problem

    return load_problem(str(ROOT / "problems" / f"{problem}.jshop")).instances[0]


@pytest.mark.sim
def test_the_domestic_robot_holds_its_parts():
    from htn.robot.arm import Arm
    from htn.robot.base import MobileBase
    from htn.robot.camera import OverviewCamera
    from htn.robot.perception import Perception
    from htn.robot.physics import Physics
    from htn.robot.pybullet_sim import PyBulletRobot
    from htn.robot.world import world_from_state

    robot = PyBulletRobot(world_from_state(_instance("bring_object").state))
    try:
        assert isinstance(robot.physics, Physics) and isinstance(robot.base, MobileBase)
        assert isinstance(robot.arm, Arm) and isinstance(robot.perception, Perception)
        assert isinstance(robot.camera, OverviewCamera)
        # the parts share one physics client and one base, handed to them
        assert robot.arm.physics is robot.physics and robot.arm.base is robot.base
        assert robot.perception.base is robot.base and robot.camera.base is robot.base
        assert robot.base.mounted() == [(robot.arm.body, robot.base.mount_pos((0.2, 0.0, 0.48)))]
    finally:
        robot.close()


@pytest.mark.sim
def test_the_kitchen_robot_holds_its_parts():
    from htn.robot.drawer import Drawers
    from htn.robot.kitchen_sim import KitchenRobot
    from htn.robot.table_spots import TableSpots
    from htn.robot.tray import Trays
    from htn.robot.two_arms import TwoArms
    from htn.robot.world import kitchen_world_from_state

    robot = KitchenRobot(kitchen_world_from_state(_instance("set_table_and_clean_up").state))
    try:
        assert isinstance(robot.arms, TwoArms) and isinstance(robot.drawers, Drawers)
        assert isinstance(robot.trays, Trays) and isinstance(robot.spots, TableSpots)
        assert robot.drawers.arms is robot.arms and robot.trays.arms is robot.arms
        assert [a.base for a in robot.arms.all()] == [robot.base, robot.base]
        # what a hand holds is one record, which the arm writes and the parts read
        assert robot.arms.hands is robot.spots.hands
        robot.arms.left.held = "cup"
        assert robot.arms.hands == {"left": "cup", "right": None}
        assert robot.arms.holding("cup") is robot.arms.left
    finally:
        robot.close()
