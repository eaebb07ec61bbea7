"""Two Franka Panda arms on one base (the kitchen robot): each an
:class:`~htn.robot.arm.Arm` whose joints stay where they were last commanded
(nothing pushes them around), with a side to rest at; both moved together
in joint space for the tray."""

from __future__ import annotations

import math

from .arm import ARM_JOINTS, FINGERS, Arm
from .base import MobileBase
from .faults import FaultDraws
from .physics import DT, Physics

ARM_HOMES = {  # tucked to the robot's sides, out of the head camera's view
    "left": (1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785),
    "right": (-1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785),
}
MOUNTS = {"left": (0.25, 0.2, 0.48), "right": (0.25, -0.2, 0.48)}
SIDE = {"left": 1.0, "right": -1.0}
ARM_AND_FINGERS = [*ARM_JOINTS, *FINGERS]

Hands = dict[str, str | None]  # what each hand holds (None: nothing), by arm


class SideArm(Arm):
    """The ``left`` or ``right`` arm. Its joints are commanded (``q_cmd``,
    ``f_cmd``) and every physics step puts them there again; what it holds is
    written to ``hands``, which the parts that must not count a held object
    as lying somewhere read."""

    def __init__(
        self, physics: Physics, base: MobileBase, draws: FaultDraws, name: str, hands: Hands
    ):
        self.hands = hands
        super().__init__(physics, base, draws, MOUNTS[name], name)
        self.side = SIDE[name]
        self.q_cmd: list[float] = []
        self.f_cmd = 0.0
        self.command(ARM_HOMES[name])
        self.set_fingers(0.04)

    @property
    def held(self) -> str | None:
        return self.hands[self.name]

    @held.setter
    def held(self, obj: str | None) -> None:
        self.hands[self.name] = obj

    @property
    def label(self) -> str:
        return f"the {self.name} gripper"

    def command(self, q) -> None:
        """Set the joints; every physics step keeps them there (kinematic arms)."""
        self.q_cmd = list(q)
        self.set_q(q)

    def _follow(self, q) -> None:
        self.command(q)

    def set_fingers(self, width: float) -> None:
        self.f_cmd = width
        super().set_fingers(width)

    def keep_joints(self) -> None:
        """Put the joints where they were commanded (before every physics step)."""
        f = self.f_cmd
        self.physics.p.resetJointStatesMultiDof(
            self.body,
            ARM_AND_FINGERS,
            [[v] for v in self.q_cmd] + [[f], [f]],
            physicsClientId=self.physics.cid,
        )

    def reachable(self, pos) -> bool:
        return self.ik(pos) is not None

    def rest(self):
        """Holding something, close to its side; else tucked."""
        if self.held is None:
            yield from self.move(ARM_HOMES[self.name], 0.7)
            return
        x, y, yaw = self.base.pose
        mx, my, _ = self.base.mount_pos(MOUNTS[self.name])
        lx, ly = -math.sin(yaw) * self.side, math.cos(yaw) * self.side
        fx, fy = math.cos(yaw), math.sin(yaw)
        if not (
            yield from self.reach([mx + 0.2 * fx + 0.25 * lx, my + 0.2 * fy + 0.25 * ly, 0.95], 0.7)
        ):
            yield from self.move(ARM_HOMES[self.name], 0.7)
        yield from self.physics.step(12)


class TwoArms:
    """The ``left`` and the ``right`` arm, by name."""

    NAMES = ("left", "right")

    def __init__(self, physics: Physics, base: MobileBase, draws: FaultDraws, hands: Hands):
        self.physics = physics
        self.hands = hands
        self.by_name = {a: SideArm(physics, base, draws, a, hands) for a in self.NAMES}
        self.left, self.right = self.by_name["left"], self.by_name["right"]

    def __getitem__(self, name: str) -> SideArm:
        return self.by_name[name]

    def all(self) -> list[SideArm]:
        return list(self.by_name.values())

    def pick(self, arm: str | None) -> str | None:
        """``arm`` if it names one, else the first free one (None: both hands are full)."""
        if arm in self.NAMES:
            return arm
        return next((a for a in self.NAMES if self.hands[a] is None), None)

    def holding(self, obj: str) -> SideArm | None:
        return next((self.by_name[a] for a in self.NAMES if self.hands[a] == obj), None)

    def held_objects(self) -> list[str]:
        return [o for o in self.hands.values() if o]

    def keep_joints(self) -> None:
        for arm in self.by_name.values():  # nothing pushes the arms around
            arm.keep_joints()

    def move_both(self, goals: dict, seconds: float):
        """The arms of ``goals`` (name -> joints) at once, in joint space."""
        p, c = self.physics.p, self.physics.cid
        starts = {
            a: [p.getJointState(self.by_name[a].body, j, physicsClientId=c)[0] for j in ARM_JOINTS]
            for a in goals
        }
        n = max(1, int(seconds / DT))
        for i in range(1, n + 1):
            k = i / n
            for a, q in goals.items():
                self.by_name[a].command([s + (g - s) * k for s, g in zip(starts[a], q)])
            yield from self.physics.step()

    def home_both(self):
        return self.move_both({a: ARM_HOMES[a] for a in self.NAMES}, 0.8)
