"""The robot interface: the skills the domain's operators need, and what the
robot can observe of the world to monitor them.

A skill returns a :class:`SkillResult`: ``ok`` is the robot's own belief that it
finished (``False`` only for an internal failure, e.g. an unreachable arm
pose). Whether the effect really happened is for a monitor to decide, using
the ``observe``/``check_*`` methods, which look at the world itself.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
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


class Robot(ABC):
    """Skills (act) and checks (observe) of a mobile manipulator."""

    world: Any
    sim_time: float = 0.0

    # ---- skills
    @abstractmethod
    def move_base(self, place: str) -> SkillResult: ...

    @abstractmethod
    def detect_object(self, obj: str, furniture: str) -> SkillResult: ...

    @abstractmethod
    def grasp(self, obj: str, furniture: str) -> SkillResult: ...

    @abstractmethod
    def place_object(self, obj: str, furniture: str) -> SkillResult: ...

    @abstractmethod
    def find_person(self, person: str) -> SkillResult: ...

    @abstractmethod
    def hand_over(self, obj: str, person: str) -> SkillResult: ...

    @abstractmethod
    def say(self, message: str) -> SkillResult: ...

    @abstractmethod
    def hold(self) -> None:
        """Stop all motion and keep the current pose (after a failure)."""

    # ---- checks used by monitors
    @abstractmethod
    def check_base_at(self, place: str) -> Check: ...

    @abstractmethod
    def check_no_collision(self) -> Check: ...

    @abstractmethod
    def check_in_gripper(self, obj: str) -> Check: ...

    @abstractmethod
    def check_on(self, obj: str, furniture: str) -> Check: ...

    @abstractmethod
    def check_handed(self, obj: str, person: str) -> Check: ...

    @abstractmethod
    def check_person_visible(self, person: str) -> Check: ...

    @abstractmethod
    def check_detection(self, obj: str) -> Check: ...

    @abstractmethod
    def check_said(self, message: str) -> Check: ...

    # ---- kitchen skills: arms, containers, a tray. A robot that lacks one
    # reports it as an internal failure (the action ends "failed").
    def open_container(self, container: str) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot open containers")

    def close_container(self, container: str) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot close containers")

    def put_on_tray(self, obj: str, tray: str, arm: Optional[str] = None) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot use a tray")

    def lift_tray(self, tray: str) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot use a tray")

    def lower_tray(self, tray: str, where: str) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot use a tray")

    def take_from_tray(self, obj: str, tray: str, arm: Optional[str] = None) -> SkillResult:
        return SkillResult(False, f"{type(self).__name__} cannot use a tray")

    def check_opened(self, container: str, opened: bool) -> Check:
        return Check(False, "not observable on this robot")

    def check_on_tray(self, obj: str, tray: str) -> Check:
        return Check(False, "not observable on this robot")

    def check_tray_carried(self, tray: str, carried: bool, where: Optional[str] = None) -> Check:
        return Check(False, "not observable on this robot")

    # ---- state estimation for replanning
    @abstractmethod
    def observe(self) -> list[tuple[str, tuple]]:
        """Facts of the domain's dynamic predicates, as the robot perceives them."""

    def close(self) -> None:
        pass

    def snapshot(self, path: str) -> Optional[str]:
        return None
