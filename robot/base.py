"""The mobile base both simulated robots stand on: a Husky that turns and
drives, carrying what is mounted on it (one arm or two).

Motion is velocity-controlled (:mod:`htn.robot.drive`): the base's speeds
(``_speeds``) and accelerations (``_accelerations``) bound a trapezoidal
profile, and a motion ends within the controller's goal tolerance, not on
the goal: the monitors measure the pose it ends in. Collisions do not stop
the base by themselves: the task executor's hold-monitor ``no_collision``
watches every drive and preempts it at the first contact. Two faults live
here: a navigation that stops short of its goal (``nav``) and an object that
slips out of a gripper while the base drives with it (``slip``, see
:meth:`MobileBase._carry_slip`).
"""
from __future__ import annotations

import math
from typing import Optional

from .interface import Check, check
from .drive import Limits, angle_diff, drive_steps, turn_steps
from .physics import DT, yaw_quat

BASE_SPEED = 1.0          # m/s
TURN_SPEED = 2.0          # rad/s
BASE_ACCEL = 1.0          # m/s^2
TURN_ACCEL = 4.0          # rad/s^2
POSE_TOLERANCE = 0.05     # m
YAW_TOLERANCE = 0.05      # rad
BASE_Z = 0.14             # husky base height


class MobileBase:
    """Base motion, its two faults, and the checks on where the base is."""

    def _load_base(self, x: float, y: float, yaw: float) -> None:
        self.base = [x, y, yaw]
        self.husky = self.p.loadURDF("husky/husky.urdf", [x, y, BASE_Z], yaw_quat(self.p, yaw),
                                     useFixedBase=True, physicsClientId=self.cid)

    def _put_base(self, x: float, y: float, yaw: float) -> None:
        p, c = self.p, self.cid
        yaw = angle_diff(yaw, 0.0)
        self.base = [x, y, yaw]
        q = yaw_quat(p, yaw)
        p.resetBasePositionAndOrientation(self.husky, [x, y, BASE_Z], q, physicsClientId=c)
        for body, pos in self._mounted():
            p.resetBasePositionAndOrientation(body, pos, q, physicsClientId=c)

    def _mounted(self) -> list:   # pragma: no cover - each robot says what it carries
        """(body, position) of what is mounted on the base, for its current pose."""
        raise NotImplementedError

    def _speeds(self) -> tuple[float, float]:
        """Base speed (m/s) and turning speed (rad/s)."""
        return BASE_SPEED, TURN_SPEED

    def _accelerations(self) -> tuple[float, float]:
        """Base acceleration (m/s^2) and turning acceleration (rad/s^2)."""
        return BASE_ACCEL, TURN_ACCEL

    def _limits(self) -> Limits:
        return Limits(*self._speeds(), *self._accelerations())

    def _turn_to(self, yaw: float):
        x, y, start = self.base
        for heading in turn_steps(start, yaw, self._limits(), DT):
            self._put_base(x, y, heading)
            yield from self._step()

    def _drive(self, gx: float, gy: float, fraction: float = 1.0, slip: Optional[float] = None):
        """Drive straight to (gx, gy), forwards or backwards, or ``fraction``
        of the way; an object scheduled to slip (``slip``: fraction of the
        drive) falls there."""
        x0, y0, _ = self.base
        goal = (x0 + (gx - x0) * fraction, y0 + (gy - y0) * fraction)
        total = math.hypot(goal[0] - x0, goal[1] - y0)
        for x, y, yaw, travelled in drive_steps(tuple(self.base), goal, self._limits(), DT):
            self._put_base(x, y, yaw)
            if slip is not None and travelled >= slip * total:
                self._drop_while_carrying()
                slip = None
            yield from self._step()

    def _face(self, x: float, y: float):
        return self._turn_to(math.atan2(y - self.base[1], x - self.base[0]))

    # ------------------------------------------------------------ faults
    def _nav_fault(self, place: str) -> float:
        """The fraction of the way to ``place`` a drive gets (1.0 without a fault)."""
        if self.faults.nav and self.rng.random() < self.faults.nav:
            fraction = self.rng.uniform(0.4, 0.85)
            self.inject("nav", f"stops at {fraction:.0%} of the way to {place}")
            return fraction
        return 1.0

    def _carry_slip(self) -> Optional[float]:
        """When the base drives with an object in a gripper, the object slips
        with probability ``slip``, at a random point of the drive."""
        if self._carried_objects() and self.faults.slip and self.rng.random() < self.faults.slip:
            return self.rng.uniform(0.1, 0.9)
        return None

    # ------------------------------------------------------------ what touches the base
    def _base_contacts(self) -> list[str]:
        """Names of bodies the base or what is mounted on it touches (the
        floor and what the robot carries excepted)."""
        p, c = self.p, self.cid
        mine = [self.husky, *(body for body, _ in self._mounted())]
        own = {self.plane, *mine} | self._carried_bodies()
        names = []
        for body in mine:
            for cp in p.getContactPoints(bodyA=body, physicsClientId=c):
                if cp[2] not in own:
                    names.append(self.bodies_named.get(cp[2], str(cp[2])))
        return sorted(set(names))

    def _place_here(self) -> Optional[str]:
        """The named place whose pose the base is at, if any."""
        x, y, yaw = self.base
        for pl in self.world.places.values():
            if math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE and \
                    abs(angle_diff(pl.theta, yaw)) <= YAW_TOLERANCE:
                return pl.name
        return None

    # ------------------------------------------------------------ checks
    def _measured_pose(self) -> tuple[float, float, float]:
        """The base's pose as PyBullet has it (x, y, yaw)."""
        p, c = self.p, self.cid
        (x, y, _), q = p.getBasePositionAndOrientation(self.husky, physicsClientId=c)
        return x, y, p.getEulerFromQuaternion(q)[2]

    def _stopped_at(self) -> str:
        x, y, yaw = self._measured_pose()
        return f"stopped at x {x:.3f} m, y {y:.3f} m, heading {yaw:.3f} rad"

    @check("base_at")
    def check_base_at(self, place: str) -> Check:
        """Is the base at ``place``'s pose, within the tolerances? Measured:
        the distance and heading error of the base's pose in the world."""
        goal = self.world.place(place)
        x, y, yaw = self._measured_pose()
        err = math.hypot(goal.x - x, goal.y - y)
        yaw_err = abs(angle_diff(goal.theta, yaw))
        ok = err <= POSE_TOLERANCE and yaw_err <= YAW_TOLERANCE
        return Check(ok, f"base measured {err:.4f} m, {yaw_err:.4f} rad from {place} "
                         f"(tolerance {POSE_TOLERANCE} m, {YAW_TOLERANCE} rad)")

    @check("no_collision")
    def check_no_collision(self) -> Check:
        hits = self._base_contacts()
        return Check(not hits, "touching " + ", ".join(hits) if hits else "no contact")
