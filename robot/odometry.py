"""How far a simulated robot's base and grippers have travelled.

The navigation and manipulation costs of the plan-transformations paper
(Section IV-A: distances between key points of the base and gripper
trajectories), measured here at every physics step of the motion instead of
between key points. The odometer samples after each step of the
:class:`~htn.robot.physics.Physics` clock (its ``after_step`` hook), so every
base and arm motion of both PyBullet robots is counted.
"""

from __future__ import annotations

import math

from .arm import EE_LINK
from .base import MobileBase
from .physics import Physics


class Odometry:
    """``base``: the path of the base in the plane (m); ``grippers``: the
    summed paths of the gripper frames relative to the base (m), so that
    driving with still arms adds nothing to it."""

    def __init__(self, physics: Physics, base: MobileBase):
        self._physics, self._base = physics, base
        self.base = 0.0
        self.grippers = 0.0
        self._last: tuple | None = None  # base (x, y), grippers in the base frame

    def sample(self) -> None:
        p, c = self._physics.p, self._physics.cid
        x, y, yaw = self._base.pose
        cos, sin = math.cos(yaw), math.sin(yaw)
        grippers = []
        for body, _ in self._base.mounted():  # the arms ride on the base
            gx, gy, gz = p.getLinkState(body, EE_LINK, physicsClientId=c)[4]
            dx, dy = gx - x, gy - y
            grippers.append((cos * dx + sin * dy, cos * dy - sin * dx, gz))
        if self._last is not None:
            (lx, ly), last = self._last
            self.base += math.hypot(x - lx, y - ly)
            self.grippers += sum(math.dist(a, b) for a, b in zip(grippers, last))
        self._last = ((x, y), grippers)
