"""The robot interface: the skills the domain's operators need, and what the
robot can observe of the world to monitor them.

A skill returns a :class:`SkillResult`: ``ok`` is the robot's own belief that it
finished (``False`` only for an internal failure, e.g. an unreachable arm
pose). Whether the effect really happened is for a monitor to decide, using
the ``observe``/``check_*`` methods, which look at the world itself.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Optional


@dataclass
class SkillResult:
    ok: bool
    detail: str = ""
    data: dict = field(default_factory=dict)


@dataclass
class Check:
    """A monitor's observation: did the world show the expected effect?"""
    ok: bool
    detail: str = ""


class Robot:
    """A robot back end: skills (act), checks (observe) and state estimation.

    Every robot has a clock (``sim_time``), can ``hold`` its pose and report
    what it ``observe``s of the domain's dynamic predicates. Skills and checks
    are the methods the action state machines call; a robot that lacks one
    reports an internal failure, so the action ends ``failed`` (a skill) or
    ``aborted`` (a check) instead of crashing. A robot whose
    ``executes_operator_model`` is true runs every operator through
    ``apply_operator`` / ``check_operator_effects`` (the symbolic robot).
    """

    world: Any = None
    sim_time: float = 0.0
    carrying: Optional[str] = None        # what the robot believes it carries
    executes_operator_model: bool = False

    def _lacks(self, what: str) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot {what}")

    def _unobservable(self) -> Check:
        return Check(False, f"not observable on {type(self).__name__}")

    # ---- the domestic robot's skills
    def move_base(self, place: str) -> SkillResult:
        return self._lacks("move its base")

    def detect_object(self, obj: str, furniture: str) -> SkillResult:
        return self._lacks("detect objects")

    def has_detection(self, obj: str) -> bool:
        return False

    def grasp(self, obj: str, furniture: str, arm: Optional[str] = None) -> SkillResult:
        return self._lacks("grasp")

    def place_object(self, obj: str, furniture: str, arm: Optional[str] = None) -> SkillResult:
        return self._lacks("place objects")

    def find_person(self, person: str) -> SkillResult:
        return self._lacks("look for persons")

    def hand_over(self, obj: str, person: str) -> SkillResult:
        return self._lacks("hand objects over")

    def say(self, message: str) -> SkillResult:
        return self._lacks("speak")

    # ---- the kitchen robot's skills: containers and a tray
    def open_container(self, container: str) -> SkillResult:
        return self._lacks("open containers")

    def close_container(self, container: str) -> SkillResult:
        return self._lacks("close containers")

    def put_on_tray(self, obj: str, tray: str, arm: Optional[str] = None) -> SkillResult:
        return self._lacks("use a tray")

    def lift_tray(self, tray: str) -> SkillResult:
        return self._lacks("use a tray")

    def lower_tray(self, tray: str, where: str) -> SkillResult:
        return self._lacks("use a tray")

    def take_from_tray(self, obj: str, tray: str, arm: Optional[str] = None) -> SkillResult:
        return self._lacks("use a tray")

    # ---- the operator model (see executes_operator_model)
    def apply_operator(self, name: str, args: tuple) -> SkillResult:
        return self._lacks(f"execute {name} from its operator model")

    def check_operator_effects(self, name: str, args: tuple) -> Check:
        return self._unobservable()

    def apply_internal(self, name: str, args: tuple) -> None:
        """An internal (``!!``) step was applied to the belief state; a robot
        whose world is the operator model applies it too."""

    # ---- checks used by monitors
    def check_base_at(self, place: str) -> Check:
        return self._unobservable()

    def check_no_collision(self) -> Check:
        return self._unobservable()

    def check_in_gripper(self, obj: str) -> Check:
        return self._unobservable()

    def check_on(self, obj: str, furniture: str) -> Check:
        return self._unobservable()

    def check_handed(self, obj: str, person: str) -> Check:
        return self._unobservable()

    def check_person_visible(self, person: str) -> Check:
        return self._unobservable()

    def check_detection(self, obj: str) -> Check:
        return self._unobservable()

    def check_said(self, message: str) -> Check:
        return self._unobservable()

    def check_opened(self, container: str, opened: bool) -> Check:
        return self._unobservable()

    def check_on_tray(self, obj: str, tray: str) -> Check:
        return self._unobservable()

    def check_tray_carried(self, tray: str, carried: bool, where: Optional[str] = None) -> Check:
        return self._unobservable()

    # ---- control and state estimation
    def hold(self) -> None:
        """Stop all motion and keep the current pose (after a failure)."""

    def observe(self) -> list[tuple[str, tuple]]:
        """Facts of the domain's dynamic predicates, as the robot perceives them."""
        return []

    def injected_faults(self) -> list[dict]:
        """The faults injected so far (kind, sim time, detail), oldest first."""
        return list(getattr(self, "injected", []))

    def close(self) -> None:
        pass

    def snapshot(self, path: str) -> Optional[str]:
        return None
