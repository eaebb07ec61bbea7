"""Action state machines: one per operator, one life cycle for all.

As in the paper (section 4), every operator is executed by a small state
machine with three states: **execute** the action, run its **monitor**, and
**report**. The outcomes are one enum for every action:

* ``finished``  - the action reports that it is done (feedback);
* ``verified``  - its monitor observed the expected effect in the world;
* ``failed``    - the action itself failed (internal error);
* ``aborted``   - it finished, but the monitor did not observe the effect;
* ``retrying``  - it will be tried again (up to the operator's retry limit).

Registering an action for a new operator is a few lines::

    @action("!wave")
    class Wave(ActionMachine):
        def execute(self, robot, hand):
            return robot.wave(hand)
        def monitor(self, robot, hand):
            return robot.check_waving(hand)

Other packages register theirs through the entry-point group ``htn.actions``:
each entry point names a module (importing it runs its ``@action``
decorators) or a function called once with no arguments. They are loaded the
first time a machine is looked up.
"""
from __future__ import annotations

from enum import Enum
from typing import Callable, Optional

from htn.robot.interface import Check, Robot, SkillResult


class Outcome(str, Enum):
    FINISHED = "finished"
    VERIFIED = "verified"
    FAILED = "failed"
    ABORTED = "aborted"
    RETRYING = "retrying"


class ActionMachine:
    """Execute -> monitor -> report, for one operator instance.

    Subclasses define :meth:`execute` (call a robot skill) and :meth:`monitor`
    (check the world); arguments are the plan step's parameters.
    """

    name = ""

    def execute(self, robot: Robot, *args) -> SkillResult:  # pragma: no cover - abstract
        raise NotImplementedError

    def monitor(self, robot: Robot, *args) -> Check:  # pragma: no cover - abstract
        raise NotImplementedError

    def run(self, robot: Robot, args: tuple, emit: Callable[[str, str], None]) -> Outcome:
        """One attempt: the three states; returns verified, failed or aborted."""
        try:
            result = self.execute(robot, *args)
        except TypeError as exc:  # wrong number of parameters in the plan step
            emit(Outcome.FAILED.value, f"bad parameters: {exc}")
            return Outcome.FAILED
        if not result.ok:
            emit(Outcome.FAILED.value, result.detail)
            return Outcome.FAILED
        emit(Outcome.FINISHED.value, result.detail)
        check = self.monitor(robot, *args)
        if check.ok:
            emit(Outcome.VERIFIED.value, check.detail)
            return Outcome.VERIFIED
        emit(Outcome.ABORTED.value, check.detail)
        return Outcome.ABORTED


REGISTRY: dict[tuple, type] = {}      # (domain or None, operator) -> machine class


def action(operator: str, domain: Optional[str] = None):
    """Class decorator: register an :class:`ActionMachine` for an operator name,
    for every domain or (``domain=``) for one domain whose operator of the same
    name means something else."""
    def register(cls):
        cls.name = operator
        REGISTRY[(domain, operator)] = cls
        return cls
    return register


_plugins_loaded = False


def load_plugins() -> None:
    """Load the ``htn.actions`` entry points (once)."""
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    import inspect
    from importlib.metadata import entry_points

    from htn.jshop.errors import HtnError
    for ep in entry_points(group="htn.actions"):
        try:
            obj = ep.load()
            if callable(obj) and not inspect.isclass(obj):
                obj()
        except Exception as exc:   # a broken plugin: say which, no traceback
            raise HtnError(f"action plugin '{ep.name}' ({ep.value}) failed to load: "
                           f"{type(exc).__name__}: {exc}")


def machine_for(operator: str, domain: Optional[str] = None,
                robot: Optional[Robot] = None) -> Optional[ActionMachine]:
    """The action state machine for an operator: the operator model's on a
    robot that executes it, else the one registered for this domain, else
    the one registered for every domain, else None."""
    if robot is not None and robot.executes_operator_model:
        return OperatorModelAction(operator)
    load_plugins()
    cls = REGISTRY.get((domain, operator)) or REGISTRY.get((None, operator))
    return cls() if cls else None


class OperatorModelAction(ActionMachine):
    """Any operator, on a robot whose world is the domain's operator model:
    execute applies the operator's effects, the monitor checks its add and
    delete lists against the world (see :mod:`htn.robot.symbolic`)."""

    def __init__(self, operator: str):
        self.name = operator

    def execute(self, robot, *args):
        return robot.apply_operator(self.name, args)

    def monitor(self, robot, *args):
        return robot.check_operator_effects(self.name, args)


def _all(*checks: Check) -> Check:
    bad = [c for c in checks if not c.ok]
    return Check(not bad, "; ".join(c.detail for c in (bad or checks)))


# ---------------------------------------------------------------- the domestic robot

@action("!move_base")
class MoveBase(ActionMachine):
    def execute(self, robot, who, start, goal):
        return robot.move_base(goal)

    def monitor(self, robot, who, start, goal):
        checks = [robot.check_base_at(goal), robot.check_no_collision()]
        if robot.carrying:   # what the robot believes it carries must still be in the hand
            checks.append(robot.check_in_gripper(robot.carrying))
        return _all(*checks)


@action("!detect_object")
class DetectObject(ActionMachine):
    def execute(self, robot, who, obj, furniture):
        return robot.detect_object(obj, furniture)

    def monitor(self, robot, who, obj, furniture):
        return robot.check_detection(obj)


@action("!grasp")
class Grasp(ActionMachine):
    def execute(self, robot, who, obj, furniture):
        if not robot.has_detection(obj):   # e.g. on a retry: look again first
            robot.detect_object(obj, furniture)
        return robot.grasp(obj, furniture)

    def monitor(self, robot, who, obj, furniture):
        return robot.check_in_gripper(obj)


@action("!place")
class Place(ActionMachine):
    def execute(self, robot, who, obj, furniture):
        return robot.place_object(obj, furniture)

    def monitor(self, robot, who, obj, furniture):
        return robot.check_on(obj, furniture)


@action("!find_person")
class FindPerson(ActionMachine):
    def execute(self, robot, who, person, place):
        return robot.find_person(person)

    def monitor(self, robot, who, person, place):
        return robot.check_person_visible(person)


@action("!hand_over")
class HandOver(ActionMachine):
    def execute(self, robot, who, obj, person):
        return robot.hand_over(obj, person)

    def monitor(self, robot, who, obj, person):
        return robot.check_handed(obj, person)


@action("!say")
class Say(ActionMachine):
    def execute(self, robot, who, message):
        return robot.say(message)

    def monitor(self, robot, who, message):
        return robot.check_said(message)


# ---------------------------------------------------------------- the kitchen (pick and place)

@action("!navigate", domain="kitchen")
class Navigate(ActionMachine):
    def execute(self, robot, start, goal):
        return robot.move_base(goal)

    def monitor(self, robot, start, goal):
        return robot.check_base_at(goal)


@action("!look-for", domain="kitchen")
class LookFor(ActionMachine):
    def execute(self, robot, obj, area):
        return robot.detect_object(obj, area)

    def monitor(self, robot, obj, area):
        return robot.check_detection(obj)


@action("!grasp", domain="kitchen")
class GraspWithArm(ActionMachine):
    def execute(self, robot, obj, area, arm):
        return robot.grasp(obj, area, arm)

    def monitor(self, robot, obj, area, arm):
        return robot.check_in_gripper(obj)


@action("!grasp-from", domain="kitchen")
class GraspFromContainer(ActionMachine):
    def execute(self, robot, obj, container, arm):
        return robot.grasp(obj, container, arm)

    def monitor(self, robot, obj, container, arm):
        return robot.check_in_gripper(obj)


@action("!place", domain="kitchen")
class PlaceWithArm(ActionMachine):
    def execute(self, robot, obj, area, arm):
        return robot.place_object(obj, area, arm)

    def monitor(self, robot, obj, area, arm):
        return robot.check_on(obj, area)


@action("!open", domain="kitchen")
class OpenContainer(ActionMachine):
    def execute(self, robot, container):
        return robot.open_container(container)

    def monitor(self, robot, container):
        return robot.check_opened(container, True)


@action("!close", domain="kitchen")
class CloseContainer(ActionMachine):
    def execute(self, robot, container):
        return robot.close_container(container)

    def monitor(self, robot, container):
        return robot.check_opened(container, False)


@action("!put-on-tray", domain="kitchen")
class PutOnTray(ActionMachine):
    def execute(self, robot, obj, tray, arm):
        return robot.put_on_tray(obj, tray, arm)

    def monitor(self, robot, obj, tray, arm):
        return robot.check_on_tray(obj, tray)


@action("!lift-tray", domain="kitchen")
class LiftTray(ActionMachine):
    def execute(self, robot, tray):
        return robot.lift_tray(tray)

    def monitor(self, robot, tray):
        return robot.check_tray_carried(tray, True)


@action("!lower-tray", domain="kitchen")
class LowerTray(ActionMachine):
    def execute(self, robot, tray, area):
        return robot.lower_tray(tray, area)

    def monitor(self, robot, tray, area):
        return robot.check_tray_carried(tray, False, area)


@action("!take-from-tray", domain="kitchen")
class TakeFromTray(ActionMachine):
    def execute(self, robot, obj, tray, arm):
        return robot.take_from_tray(obj, tray, arm)

    def monitor(self, robot, obj, tray, arm):
        return robot.check_in_gripper(obj)
