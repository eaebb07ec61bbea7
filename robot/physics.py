"""The PyBullet side of the simulated robots: the physics client, its clock,
and the bodies both robots build their worlds from (floor, tables, cylinders).

Every other part of a robot is handed the :class:`Physics` it acts in. The
clock advances only through :meth:`Physics.step`, a generator that runs one
physics step (``DT``) per ``next()``: skills ``yield from`` it, so the task
executor can tick a skill and preempt it between two steps. World building,
which happens before anything is ticked, runs its steps to the end with
:func:`~htn.robot.interface.complete`. What must happen at every step (the
kitchen's arms keep their joints, a carried tray follows the hand, the
odometer samples) hooks into ``before_step`` and ``after_step``.
"""

from __future__ import annotations

import ctypes
import os
import sys
from collections.abc import Callable
from contextlib import contextmanager

import numpy as np

from .interface import complete

DT = 1.0 / 120.0  # physics step; motion is kinematic, so 120 Hz is stable
STEPS_PER_TICK = 4  # a tick of the behaviour tree: 1/30 s of simulated time


@contextmanager
def quiet_fds():
    """Silence C-level output on fds 1 and 2 (PyBullet prints banners and warnings)."""
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        libc.fflush(None)
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, devnull):
            os.close(fd)


def yaw_quat(p, yaw: float):
    return p.getQuaternionFromEuler((0.0, 0.0, yaw))


class Physics:
    """A PyBullet client with a clock, and the named bodies of its world."""

    def __init__(self, gui: bool):
        with quiet_fds():  # importing pybullet prints its build time on fd 1
            import pybullet as p
            import pybullet_data
        self.p = p
        self.sim_time = 0.0
        with quiet_fds():
            self.cid: int = p.connect(p.GUI if gui else p.DIRECT)
        if self.cid < 0:
            from htn.jshop.language.errors import HtnError

            raise HtnError(
                "--gui: PyBullet cannot open a window on display "
                f"{os.environ.get('DISPLAY', '(none)')!r}"
            )
        p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=self.cid)
        self.plane: int | None = None
        self.body_of: dict[str, int] = {}
        self.bodies_named: dict[int, str] = {}  # see name_bodies
        self.furniture_top: dict[str, float] = {}
        self.before_step: list[Callable[[], None]] = []
        self.after_step: list[Callable[[], None]] = []

    def build_ground(self) -> None:
        """Gravity, the clock and the floor; no bodies named yet."""
        p, c = self.p, self.cid
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(DT, physicsClientId=c)
        self.plane = p.loadURDF("plane.urdf", physicsClientId=c)

    def name_bodies(self) -> None:
        """Names by body, once the world is built (for contacts and logs)."""
        self.bodies_named = {v: k for k, v in self.body_of.items()}

    def load_table(self, name: str, x: float, y: float, yaw: float = 0.0) -> int:
        p, c = self.p, self.cid
        bid = p.loadURDF(
            "table/table.urdf", [x, y, 0.0], yaw_quat(p, yaw), useFixedBase=True, physicsClientId=c
        )
        self.body_of[name] = bid
        self.furniture_top[name] = p.getAABB(bid, physicsClientId=c)[1][2]
        return bid

    def make_cylinder(
        self, r: float, h: float, mass: float, rgba, x: float, y: float, z: float
    ) -> int:
        p, c = self.p, self.cid
        col = p.createCollisionShape(p.GEOM_CYLINDER, radius=r, height=h, physicsClientId=c)
        vis = p.createVisualShape(
            p.GEOM_CYLINDER, radius=r, length=h, rgbaColor=rgba, physicsClientId=c
        )
        bid = p.createMultiBody(mass, col, vis, [x, y, z], physicsClientId=c)
        p.changeDynamics(bid, -1, lateralFriction=1.0, physicsClientId=c)
        return bid

    def boxes(self, parts, mass: float, pos, yaw: float, rgba) -> int:
        """A rigid body made of boxes: parts are (half extents, offset) in the body frame."""
        p, c = self.p, self.cid
        n = len(parts)
        col = p.createCollisionShapeArray(
            [p.GEOM_BOX] * n,
            halfExtents=[h for h, _ in parts],
            collisionFramePositions=[o for _, o in parts],
            physicsClientId=c,
        )
        vis = p.createVisualShapeArray(
            [p.GEOM_BOX] * n,
            halfExtents=[h for h, _ in parts],
            visualFramePositions=[o for _, o in parts],
            rgbaColors=[rgba] * n,
            physicsClientId=c,
        )
        return p.createMultiBody(mass, col, vis, pos, yaw_quat(p, yaw), physicsClientId=c)

    # ------------------------------------------------------------ clock
    def physics_step(self) -> None:
        for hook in self.before_step:
            hook()
        self.p.stepSimulation(physicsClientId=self.cid)
        self.sim_time += DT
        for hook in self.after_step:
            hook()

    def step(self, n: int = 1):
        """Advance the simulation ``n`` steps, yielding after each."""
        for _ in range(n):
            self.physics_step()
            yield

    def settle(self, seconds: float):
        return self.step(int(seconds / DT))

    def run(self, ticking):
        """Run steps to their end now (world building, outside any tick)."""
        return complete(ticking)

    # ------------------------------------------------------------ bodies
    def pos(self, body: int) -> np.ndarray:
        return np.array(self.p.getBasePositionAndOrientation(body, physicsClientId=self.cid)[0])

    def body_pos(self, name: str) -> np.ndarray:
        return self.pos(self.body_of[name])

    def touching(self, a: int, b: int) -> bool:
        return bool(self.p.getContactPoints(bodyA=a, bodyB=b, physicsClientId=self.cid))

    def on_top(self, body: int, furniture: str) -> bool:
        """Does ``body`` rest on the top of ``furniture`` (a contact at its height)?"""
        top_body = self.body_of.get(furniture)
        if top_body is None or furniture not in self.furniture_top:
            return False
        top = self.furniture_top[furniture]
        return any(
            cp[5][2] >= top - 0.02
            for cp in self.p.getContactPoints(bodyA=body, bodyB=top_body, physicsClientId=self.cid)
        )

    def close(self) -> None:
        try:
            self.p.disconnect(physicsClientId=self.cid)
        except Exception:  # already disconnected
            pass


def open_box(hu: float, hv: float, hz: float, wall: float = 0.006) -> list:
    """Bottom and four walls of an open-top box (body frame: x = u, y = v), for
    :meth:`Physics.boxes`."""
    return [
        ((hu, hv, wall / 2), (0, 0, wall / 2)),
        ((wall / 2, hv, hz), (hu - wall / 2, 0, hz)),
        ((wall / 2, hv, hz), (-hu + wall / 2, 0, hz)),
        ((hu, wall / 2, hz), (0, hv - wall / 2, hz)),
        ((hu, wall / 2, hz), (0, -hv + wall / 2, hz)),
    ]
