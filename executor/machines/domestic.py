"""Action state machines of the domestic robot domain (``domains/domestic.jshop``):
the paper's RoboCup@Home operators on the PyBullet domestic robot."""

from __future__ import annotations

from htn.robot.interface import Check, Robot, SkillRun

from .base import ActionMachine, HoldMonitor, action, all_of, carried_by


def no_collision(robot: Robot) -> list[HoldMonitor]:
    return [("no collision", lambda: robot.check("no_collision"))]


# (holding ROBOT-OR-ARM OBJECT): what the robot carries, checked while it acts
carried_by("holding", domain="domestic")


@action("!move_base")
class MoveBase(ActionMachine):
    def execute(self, robot: Robot, who: str, start: str, goal: str) -> SkillRun:
        return robot.act("move_base", goal)

    def monitor(self, robot: Robot, who: str, start: str, goal: str) -> Check:
        return all_of(robot.check("base_at", goal), robot.check("no_collision"))

    def holds(self, robot: Robot, who: str, start: str, goal: str) -> list[HoldMonitor]:
        return no_collision(robot)


@action("!detect_object")
class DetectObject(ActionMachine):
    def execute(self, robot: Robot, who: str, obj: str, furniture: str) -> SkillRun:
        return robot.act("detect_object", obj, furniture)

    def monitor(self, robot: Robot, who: str, obj: str, furniture: str) -> Check:
        return robot.check("detection", obj)


@action("!grasp")
class Grasp(ActionMachine):
    def execute(self, robot: Robot, who: str, obj: str, furniture: str) -> SkillRun:
        return robot.act("grasp", obj, furniture)

    def monitor(self, robot: Robot, who: str, obj: str, furniture: str) -> Check:
        return robot.check("in_gripper", obj)


@action("!place")
class Place(ActionMachine):
    def execute(self, robot: Robot, who: str, obj: str, furniture: str) -> SkillRun:
        return robot.act("place_object", obj, furniture)

    def monitor(self, robot: Robot, who: str, obj: str, furniture: str) -> Check:
        return robot.check("on", obj, furniture)


@action("!find_person")
class FindPerson(ActionMachine):
    def execute(self, robot: Robot, who: str, person: str, place: str) -> SkillRun:
        return robot.act("find_person", person)

    def monitor(self, robot: Robot, who: str, person: str, place: str) -> Check:
        return robot.check("person_visible", person)


@action("!hand_over")
class HandOver(ActionMachine):
    def execute(self, robot: Robot, who: str, obj: str, person: str) -> SkillRun:
        return robot.act("hand_over", obj, person)

    def monitor(self, robot: Robot, who: str, obj: str, person: str) -> Check:
        return robot.check("handed", obj, person)


@action("!say")
class Say(ActionMachine):
    def execute(self, robot: Robot, who: str, message: str) -> SkillRun:
        return robot.act("say", message)

    def monitor(self, robot: Robot, who: str, message: str) -> Check:
        return robot.check("said", message)
