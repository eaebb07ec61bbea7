"""The mobile base both simulated robots stand on: a Husky that turns and
drives, carrying what is mounted on it (one arm or two, see :meth:`MobileBase.mount`).

Motion is velocity-controlled (:mod:`htn.robot.drive`): the base's speeds
(``_speeds``) and accelerations (``_accelerations``) bound a trapezoidal
profile, and a motion ends within the controller's goal tolerance, not on
the goal: the monitors measure the pose it ends in. Collisions do not stop
the base by themselves: the task executor's hold-monitor ``no_collision``
watches every drive and preempts it at the first contact. Two faults live
here: a navigation that stops short of its goal (``nav``) and an object that
slips out of a gripper while the base drives with it (``slip``, see
:meth:`MobileBase.carry_slip`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from .drive import Limits, angle_diff, drive_steps, turn_steps
from .faults import FaultDraws
from .interface import Check
from .physics import DT, Physics, yaw_quat
from .world import Place, World

BASE_SPEED = 1.0  # m/s
TURN_SPEED = 2.0  # rad/s
BASE_ACCEL = 1.0  # m/s^2
TURN_ACCEL = 4.0  # rad/s^2
POSE_TOLERANCE = 0.05  # m
YAW_TOLERANCE = 0.05  # rad
BASE_Z = 0.14  # husky base height
LIMITS = Limits(BASE_SPEED, TURN_SPEED, BASE_ACCEL, TURN_ACCEL)

Offset = tuple[float, float, float]  # where a body is mounted, in the base's frame


class MobileBase:
    """Base motion, its two faults, and the checks on where the base is.
    ``limits`` says how fast it may move now (the kitchen robot's depend on
    whether it carries a tray)."""

    def __init__(
        self,
        physics: Physics,
        world: World,
        draws: FaultDraws,
        start: Place,
        limits: Callable[[], Limits] = lambda: LIMITS,
    ):
        self.physics, self.world, self.draws = physics, world, draws
        self.limits = limits
        self.pose = [start.x, start.y, start.theta]  # x, y, yaw as commanded
        p = physics.p
        self.body: int = p.loadURDF(
            "husky/husky.urdf",
            [start.x, start.y, BASE_Z],
            yaw_quat(p, start.theta),
            useFixedBase=True,
            physicsClientId=physics.cid,
        )
        self._mounts: list[tuple[int, Offset]] = []

    # ------------------------------------------------------------ what rides on it
    def mount_pos(self, offset: Offset, pose=None) -> list[float]:
        """Where a body mounted at ``offset`` is, the base at ``pose`` (default: now)."""
        x, y, yaw = pose or self.pose
        mu, mv, mz = offset
        return [
            x + mu * math.cos(yaw) - mv * math.sin(yaw),
            y + mu * math.sin(yaw) + mv * math.cos(yaw),
            mz,
        ]

    def mount(self, body: int, offset: Offset) -> None:
        """Carry ``body`` at ``offset``: it moves with the base from now on."""
        self._mounts.append((body, offset))

    def mounted(self) -> list[tuple[int, list[float]]]:
        """(body, position) of what is mounted on the base, for its current pose."""
        return [(body, self.mount_pos(offset)) for body, offset in self._mounts]

    # ------------------------------------------------------------ motion
    def put(self, x: float, y: float, yaw: float) -> None:
        p, c = self.physics.p, self.physics.cid
        yaw = angle_diff(yaw, 0.0)
        self.pose = [x, y, yaw]
        q = yaw_quat(p, yaw)
        p.resetBasePositionAndOrientation(self.body, [x, y, BASE_Z], q, physicsClientId=c)
        for body, pos in self.mounted():
            p.resetBasePositionAndOrientation(body, pos, q, physicsClientId=c)

    def turn_to(self, yaw: float):
        x, y, start = self.pose
        for heading in turn_steps(start, yaw, self.limits(), DT):
            self.put(x, y, heading)
            yield from self.physics.step()

    def drive(
        self,
        gx: float,
        gy: float,
        fraction: float = 1.0,
        slip: float | None = None,
        drop: Callable[[], None] = lambda: None,
    ):
        """Drive straight to (gx, gy), forwards or backwards, or ``fraction``
        of the way; an object scheduled to slip (``slip``: fraction of the
        drive) falls there (``drop``)."""
        x0, y0, _ = self.pose
        goal = (x0 + (gx - x0) * fraction, y0 + (gy - y0) * fraction)
        total = math.hypot(goal[0] - x0, goal[1] - y0)
        for x, y, yaw, travelled in drive_steps(tuple(self.pose), goal, self.limits(), DT):
            self.put(x, y, yaw)
            if slip is not None and travelled >= slip * total:
                drop()
                slip = None
            yield from self.physics.step()

    def face(self, x: float, y: float):
        return self.turn_to(math.atan2(y - self.pose[1], x - self.pose[0]))

    # ------------------------------------------------------------ faults
    def nav_fault(self, place: str) -> float:
        """The fraction of the way to ``place`` a drive gets (1.0 without a fault)."""
        if self.draws.happens("nav"):
            fraction = self.draws.rng.uniform(0.4, 0.85)
            self.draws.inject("nav", f"stops at {fraction:.0%} of the way to {place}")
            return fraction
        return 1.0

    def carry_slip(self, carrying: bool) -> float | None:
        """When the base drives with an object in a gripper (``carrying``), the
        object slips with probability ``slip``, at a random point of the drive."""
        if carrying and self.draws.happens("slip"):
            return self.draws.rng.uniform(0.1, 0.9)
        return None

    # ------------------------------------------------------------ where it is, what it touches
    def contacts(self, carried: set[int]) -> list[str]:
        """Names of bodies the base or what is mounted on it touches (the
        floor and what the robot carries excepted)."""
        p, c = self.physics.p, self.physics.cid
        mine = [self.body, *(body for body, _ in self.mounted())]
        own = {self.physics.plane, *mine} | carried
        names = []
        for body in mine:
            for cp in p.getContactPoints(bodyA=body, physicsClientId=c):
                if cp[2] not in own:
                    names.append(self.physics.bodies_named.get(cp[2], str(cp[2])))
        return sorted(set(names))

    def place_here(self) -> str | None:
        """The named place whose pose the base is at, if any."""
        x, y, yaw = self.pose
        for pl in self.world.places.values():
            if (
                math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE
                and abs(angle_diff(pl.theta, yaw)) <= YAW_TOLERANCE
            ):
                return pl.name
        return None

    def measured_pose(self) -> tuple[float, float, float]:
        """The base's pose as PyBullet has it (x, y, yaw)."""
        p, c = self.physics.p, self.physics.cid
        (x, y, _), q = p.getBasePositionAndOrientation(self.body, physicsClientId=c)
        return x, y, p.getEulerFromQuaternion(q)[2]

    def stopped_at(self) -> str:
        x, y, yaw = self.measured_pose()
        return f"stopped at x {x:.3f} m, y {y:.3f} m, heading {yaw:.3f} rad"

    def check_at(self, place: str) -> Check:
        """Is the base at ``place``'s pose, within the tolerances? Measured:
        the distance and heading error of the base's pose in the world."""
        goal = self.world.place(place)
        x, y, yaw = self.measured_pose()
        err = math.hypot(goal.x - x, goal.y - y)
        yaw_err = abs(angle_diff(goal.theta, yaw))
        ok = err <= POSE_TOLERANCE and yaw_err <= YAW_TOLERANCE
        return Check(
            ok,
            f"base measured {err:.4f} m, {yaw_err:.4f} rad from {place} "
            f"(tolerance {POSE_TOLERANCE} m, {YAW_TOLERANCE} rad)",
        )
