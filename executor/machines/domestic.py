"""Action state machines of the domestic robot domain (``domains/domestic.jshop``):
the paper's RoboCup@Home operators on the PyBullet domestic robot."""

from __future__ import annotations

from .base import ActionMachine, action, all_of, carried_by


def no_collision(robot):
    return [("no collision", lambda: robot.check("no_collision"))]


# (holding ROBOT-OR-ARM OBJECT): what the robot carries, checked while it acts
carried_by("holding", domain="domestic")


@action("!move_base")
class MoveBase(ActionMachine):
    def execute(self, robot, who, start, goal):
        return robot.act("move_base", goal)

    def monitor(self, robot, who, start, goal):
        return all_of(robot.check("base_at", goal), robot.check("no_collision"))

    def holds(self, robot, who, start, goal):
        return no_collision(robot)


@action("!detect_object")
class DetectObject(ActionMachine):
    def execute(self, robot, who, obj, furniture):
        return robot.act("detect_object", obj, furniture)

    def monitor(self, robot, who, obj, furniture):
        return robot.check("detection", obj)


@action("!grasp")
class Grasp(ActionMachine):
    def execute(self, robot, who, obj, furniture):
        return robot.act("grasp", obj, furniture)

    def monitor(self, robot, who, obj, furniture):
        return robot.check("in_gripper", obj)


@action("!place")
class Place(ActionMachine):
    def execute(self, robot, who, obj, furniture):
        return robot.act("place_object", obj, furniture)

    def monitor(self, robot, who, obj, furniture):
        return robot.check("on", obj, furniture)


@action("!find_person")
class FindPerson(ActionMachine):
    def execute(self, robot, who, person, place):
        return robot.act("find_person", person)

    def monitor(self, robot, who, person, place):
        return robot.check("person_visible", person)


@action("!hand_over")
class HandOver(ActionMachine):
    def execute(self, robot, who, obj, person):
        return robot.act("hand_over", obj, person)

    def monitor(self, robot, who, obj, person):
        return robot.check("handed", obj, person)


@action("!say")
class Say(ActionMachine):
    def execute(self, robot, who, message):
        return robot.act("say", message)

    def monitor(self, robot, who, message):
        return robot.check("said", message)
