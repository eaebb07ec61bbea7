"""Action state machines of the kitchen pick-and-place domain
(``domains/kitchen.jshop``): two arms, drawers and a tray."""

from __future__ import annotations

from .base import ActionMachine, action, all_of, carried_by
from .domestic import no_collision

# (holding ROBOT-OR-ARM OBJECT): what the robot carries, checked while it acts
carried_by("holding", domain="kitchen")


@action("!navigate", domain="kitchen")
class Navigate(ActionMachine):
    def execute(self, robot, start, goal):
        return robot.act("move_base", goal)

    def monitor(self, robot, start, goal):
        return all_of(robot.check("base_at", goal), robot.check("no_collision"))

    def holds(self, robot, start, goal):
        return no_collision(robot)


@action("!look-for", domain="kitchen")
class LookFor(ActionMachine):
    def execute(self, robot, obj, area):
        return robot.act("detect_object", obj, area)

    def monitor(self, robot, obj, area):
        return robot.check("detection", obj)


@action("!grasp", domain="kitchen")
class GraspWithArm(ActionMachine):
    def execute(self, robot, obj, area, arm):
        return robot.act("grasp", obj, area, arm)

    def monitor(self, robot, obj, area, arm):
        return robot.check("in_gripper", obj)


@action("!grasp-from", domain="kitchen")
class GraspFromContainer(ActionMachine):
    def execute(self, robot, obj, container, arm):
        return robot.act("grasp", obj, container, arm)

    def monitor(self, robot, obj, container, arm):
        return robot.check("in_gripper", obj)


@action("!place", domain="kitchen")
class PlaceWithArm(ActionMachine):
    def execute(self, robot, obj, area, arm):
        return robot.act("place_object", obj, area, arm)

    def monitor(self, robot, obj, area, arm):
        return robot.check("on", obj, area)


@action("!open", domain="kitchen")
class OpenContainer(ActionMachine):
    def execute(self, robot, container):
        return robot.act("open_container", container)

    def monitor(self, robot, container):
        return robot.check("opened", container, True)


@action("!close", domain="kitchen")
class CloseContainer(ActionMachine):
    def execute(self, robot, container):
        return robot.act("close_container", container)

    def monitor(self, robot, container):
        return robot.check("opened", container, False)


@action("!put-on-tray", domain="kitchen")
class PutOnTray(ActionMachine):
    def execute(self, robot, obj, tray, arm):
        return robot.act("put_on_tray", obj, tray, arm)

    def monitor(self, robot, obj, tray, arm):
        return robot.check("on_tray", obj, tray)


@action("!lift-tray", domain="kitchen")
class LiftTray(ActionMachine):
    def execute(self, robot, tray):
        return robot.act("lift_tray", tray)

    def monitor(self, robot, tray):
        return robot.check("tray_carried", tray, True)


@action("!lower-tray", domain="kitchen")
class LowerTray(ActionMachine):
    def execute(self, robot, tray, area):
        return robot.act("lower_tray", tray, area)

    def monitor(self, robot, tray, area):
        return robot.check("tray_carried", tray, False, area)


@action("!take-from-tray", domain="kitchen")
class TakeFromTray(ActionMachine):
    def execute(self, robot, obj, tray, arm):
        return robot.act("take_from_tray", obj, tray, arm)

    def monitor(self, robot, obj, tray, arm):
        return robot.check("in_gripper", obj)
