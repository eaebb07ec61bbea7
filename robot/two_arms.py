"""Two Franka Panda arms on one base (the kitchen robot): one selected at a
time for the one-arm motions of :class:`~htn.robot.arm.Arm`, both moved
together in joint space, each resting by its side or tucked away."""
from __future__ import annotations

import math
from contextlib import contextmanager
from typing import Optional

import numpy as np

from .arm import ARM_JOINTS, EE_LINK, FINGERS
from .physics import DT
from .tray import SIDE

ARM_HOMES = {   # tucked to the robot's sides, out of the head camera's view
    "left": (1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785),
    "right": (-1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785),
}
MOUNTS = {"left": (0.25, 0.2, 0.48), "right": (0.25, -0.2, 0.48)}


class TwoArms:
    """The arms part of a robot with a ``left`` and a ``right`` arm
    (``arm_body``, ``arm_held``, ``arm_grip`` per arm; ``active`` is the
    selected one)."""

    ARMS = ("left", "right")

    def _reachable(self, arm: str, pos) -> bool:
        with self._using(arm):
            return self._ik(pos) is not None

    def _arm_mount(self, arm: str, base=None) -> list[float]:
        x, y, yaw = base or self.base
        mu, mv, mz = MOUNTS[arm]
        return [x + mu * math.cos(yaw) - mv * math.sin(yaw),
                y + mu * math.sin(yaw) + mv * math.cos(yaw), mz]

    def _select(self, arm: str) -> None:
        self.active = arm
        self.arm = self.arm_body[arm]
        self.held = self.arm_held[arm]
        self._grip_constraint = self.arm_grip[arm]

    @contextmanager
    def _using(self, arm: str):
        """Run the one-arm helpers of the arm part on ``arm``."""
        previous = self.active
        self._select(arm)
        try:
            yield
        finally:
            self.arm_held[arm], self.arm_grip[arm] = self.held, self._grip_constraint
            self._select(previous)

    def _pick_arm(self, arm: Optional[str]) -> Optional[str]:
        if arm in self.ARMS:
            return arm
        return next((a for a in self.ARMS if self.arm_held[a] is None), None)

    def _rest_pose(self):
        """The selected arm: holding something, close to its side; else tucked."""
        if self.held is None:
            yield from self._move_arm(ARM_HOMES[self.active], 0.7)
            return
        x, y, yaw = self.base
        side = SIDE[self.active]
        mx, my, _ = self._arm_mount(self.active)
        lx, ly = -math.sin(yaw) * side, math.cos(yaw) * side
        fx, fy = math.cos(yaw), math.sin(yaw)
        if not (yield from self._reach([mx + 0.2 * fx + 0.25 * lx, my + 0.2 * fy + 0.25 * ly, 0.95],
                                       0.7)):
            yield from self._move_arm(ARM_HOMES[self.active], 0.7)
        yield from self._step(12)

    def _move_arms(self, goals: dict, seconds: float):
        """Both arms at once, in joint space."""
        p, c = self.p, self.cid
        starts = {a: [p.getJointState(self.arm_body[a], j, physicsClientId=c)[0]
                      for j in ARM_JOINTS] for a in goals}
        n = max(1, int(seconds / DT))
        for i in range(1, n + 1):
            k = i / n
            for a, q in goals.items():
                self._command(a, [s + (g - s) * k for s, g in zip(starts[a], q)])
            yield from self._step()

    def _command(self, arm: str, q) -> None:
        """Set an arm's joints; every physics step keeps them there (kinematic arms)."""
        self.q_cmd[arm] = list(q)
        for j, v in zip(ARM_JOINTS, q):
            self.p.resetJointState(self.arm_body[arm], j, v, physicsClientId=self.cid)

    def _move_arm(self, q_goal, seconds: float = 1.0):
        return self._move_arms({self.active: q_goal}, seconds)

    def _set_fingers(self, width: float) -> None:
        self._set_fingers_of(self.active, width)

    def _set_fingers_of(self, arm: str, width: float) -> None:
        self.f_cmd[arm] = width
        for j in FINGERS:
            self.p.resetJointState(self.arm_body[arm], j, width, physicsClientId=self.cid)

    def _ik_for(self, arm: str, pos) -> Optional[list[float]]:
        with self._using(arm):
            return self._ik(pos)

    def _ee_of(self, arm: str) -> np.ndarray:
        return np.array(self.p.getLinkState(self.arm_body[arm], EE_LINK,
                                            physicsClientId=self.cid)[4])

    def _home_both(self):
        return self._move_arms({a: ARM_HOMES[a] for a in self.ARMS}, 0.8)
