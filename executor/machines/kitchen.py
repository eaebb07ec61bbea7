"""Action state machines of the kitchen pick-and-place domain
(``domains/kitchen.jshop``): two arms, drawers and a tray."""

from __future__ import annotations

from htn.robot.interface import Check, Robot, SkillRun

from .base import ActionMachine, HoldMonitor, action, all_of, carried_by
from .domestic import no_collision

# (holding ROBOT-OR-ARM OBJECT): what the robot carries, checked while it acts
carried_by("holding", domain="kitchen")


@action("!navigate", domain="kitchen")
class Navigate(ActionMachine):
    def execute(self, robot: Robot, start: str, goal: str) -> SkillRun:
        return robot.act("move_base", goal)

    def monitor(self, robot: Robot, start: str, goal: str) -> Check:
        return all_of(robot.check("base_at", goal), robot.check("no_collision"))

    def holds(self, robot: Robot, start: str, goal: str) -> list[HoldMonitor]:
        return no_collision(robot)


@action("!look-for", domain="kitchen")
class LookFor(ActionMachine):
    def execute(self, robot: Robot, obj: str, area: str) -> SkillRun:
        return robot.act("detect_object", obj, area)

    def monitor(self, robot: Robot, obj: str, area: str) -> Check:
        return robot.check("detection", obj)


@action("!grasp", domain="kitchen")
class GraspWithArm(ActionMachine):
    def execute(self, robot: Robot, obj: str, area: str, arm: str) -> SkillRun:
        return robot.act("grasp", obj, area, arm)

    def monitor(self, robot: Robot, obj: str, area: str, arm: str) -> Check:
        return robot.check("in_gripper", obj)


@action("!grasp-from", domain="kitchen")
class GraspFromContainer(ActionMachine):
    def execute(self, robot: Robot, obj: str, container: str, arm: str) -> SkillRun:
        return robot.act("grasp", obj, container, arm)

    def monitor(self, robot: Robot, obj: str, container: str, arm: str) -> Check:
        return robot.check("in_gripper", obj)


@action("!place", domain="kitchen")
class PlaceWithArm(ActionMachine):
    def execute(self, robot: Robot, obj: str, area: str, arm: str) -> SkillRun:
        return robot.act("place_object", obj, area, arm)

    def monitor(self, robot: Robot, obj: str, area: str, arm: str) -> Check:
        return robot.check("on", obj, area)


@action("!open", domain="kitchen")
class OpenContainer(ActionMachine):
    def execute(self, robot: Robot, container: str) -> SkillRun:
        return robot.act("open_container", container)

    def monitor(self, robot: Robot, container: str) -> Check:
        return robot.check("opened", container, True)


@action("!close", domain="kitchen")
class CloseContainer(ActionMachine):
    def execute(self, robot: Robot, container: str) -> SkillRun:
        return robot.act("close_container", container)

    def monitor(self, robot: Robot, container: str) -> Check:
        return robot.check("opened", container, False)


@action("!put-on-tray", domain="kitchen")
class PutOnTray(ActionMachine):
    def execute(self, robot: Robot, obj: str, tray: str, arm: str) -> SkillRun:
        return robot.act("put_on_tray", obj, tray, arm)

    def monitor(self, robot: Robot, obj: str, tray: str, arm: str) -> Check:
        return robot.check("on_tray", obj, tray)


@action("!lift-tray", domain="kitchen")
class LiftTray(ActionMachine):
    def execute(self, robot: Robot, tray: str) -> SkillRun:
        return robot.act("lift_tray", tray)

    def monitor(self, robot: Robot, tray: str) -> Check:
        return robot.check("tray_carried", tray, True)


@action("!lower-tray", domain="kitchen")
class LowerTray(ActionMachine):
    def execute(self, robot: Robot, tray: str, area: str) -> SkillRun:
        return robot.act("lower_tray", tray, area)

    def monitor(self, robot: Robot, tray: str, area: str) -> Check:
        return robot.check("tray_carried", tray, False, area)


@action("!take-from-tray", domain="kitchen")
class TakeFromTray(ActionMachine):
    def execute(self, robot: Robot, obj: str, tray: str, arm: str) -> SkillRun:
        return robot.act("take_from_tray", obj, tray, arm)

    def monitor(self, robot: Robot, obj: str, tray: str, arm: str) -> Check:
        return robot.check("in_gripper", obj)
