"""The kitchen in PyBullet: a Husky base with two Franka Panda arms, tables,
a drawer and a tray, for the pick-and-place domain (``domains/kitchen.jshop``).

The world comes from a kitchen problem's initial state
(:func:`htn.robot.world.kitchen_world_from_state`): each working area gets a table
in front of its base pose. Objects are cylinders sized by kind (bowl, cup,
spoon, ...). A container is a drawer: an open box that slides out of a housing
standing on its area's table; closed, its contents cannot be seen or reached.
A tray is a light box with rims on its area's table.

As in :mod:`htn.robot.pybullet_sim` (whose helpers this class reuses, one arm at a
time), motion is kinematic and everything else is physics: objects rest on
tables, in the drawer and on the tray, and ride on the tray by friction while
it is carried. A grasp holds an object with a fixed constraint, created only
when both fingers touch it. The drawer moves with the gripper that pulls it
(its contents move with it); the tray, lifted with both hands, follows the
left hand through a constraint while the right hand keeps its side.

Geometry is in each area's frame: ``u`` forward from the base pose towards the
table, ``v`` to the robot's left.
"""
from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Optional

import numpy as np

from htn.jshop.errors import HtnError

from .interface import Check, SkillResult
from .pybullet_sim import (ARM_JOINTS, BASE_SPEED, BASE_Z, DT, EE_LINK, FINGERS, POSE_TOLERANCE,
                           TURN_SPEED, YAW_TOLERANCE, PyBulletRobot, _angle_diff,
                           _yaw_quat, quiet_fds)

ARM_HOMES = {   # tucked to the robot's sides, out of the head camera's view
    "left": (1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785),
    "right": (-1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785),
}
MOUNTS = {"left": (0.25, 0.2, 0.48), "right": (0.25, -0.2, 0.48)}
SIDE = {"left": 1.0, "right": -1.0}
SHAPES = {   # kind -> (radius, height, colour)
    "bowl": (0.035, 0.06, (0.95, 0.95, 0.9, 1)),
    "cup": (0.03, 0.09, (0.2, 0.4, 0.9, 1)),
    "spoon": (0.02, 0.08, (0.6, 0.6, 0.65, 1)),
}
DEFAULT_SHAPE = (0.033, 0.12, (0.9, 0.2, 0.1, 1))
ROWS = (0.70, 0.84)                 # u of the spots where objects stand on a table
SPOT_VS = tuple(round(-0.55 + 0.1 * i, 2) for i in range(12))
TRAY_HALF = (0.13, 0.17, 0.045)     # half depth (u), half width (v), rim height
TRAY_U = 0.88
TRAY_SPOTS = ((-0.06, 0.06), (-0.06, -0.06), (0.06, 0.06), (0.06, -0.06))
DRAWER_U, DRAWER_V = 0.95, 0.3      # the closed drawer's centre
DRAWER_HALF = (0.12, 0.12, 0.025)   # the drawer box: half depth, width, half wall height
HOUSING_HEIGHT = 0.11
DRAWER_OPEN = 0.23                  # how far it slides out
TRAY_BASE_SPEED, TRAY_TURN_SPEED = 0.35, 0.6
DOCK = 0.35                         # backing away from a table before turning


@dataclass
class Drawer:
    name: str
    area: str
    body: int
    out: float = 0.0                # how far it is pulled out (m)


@dataclass
class Hold:
    """The tray in both hands: it follows the left hand with this offset."""
    tray: str
    constraint: int
    rel: tuple
    riders: tuple = ()              # what stood on the tray when it was lifted


class KitchenRobot(PyBulletRobot):
    """The simulated two-armed kitchen robot; ``gui=True`` opens a window."""

    ARMS = ("left", "right")
    CAMERA_PIXELS = (160, 120)   # finer than the domestic robot's: spoons are thin

    # ------------------------------------------------------------ building
    def _build(self) -> None:
        p, c, w = self.p, self.cid, self.world
        self._build_ground()
        self.drawers: dict[str, Drawer] = {}
        self.trays: dict[str, int] = {}
        self.radius: dict[str, float] = {}
        self.height: dict[str, float] = {}
        self.believed_in: dict[str, str] = {}   # object -> container it was seen to be in
        self.hold_tray: Optional[Hold] = None
        self.arm_held: dict[str, Optional[str]] = {a: None for a in self.ARMS}
        for f in w.furniture.values():
            yaw = w.places[f.approach].theta
            bid = p.loadURDF("table/table.urdf", [f.x, f.y, 0.0], _yaw_quat(p, yaw + math.pi / 2),
                             useFixedBase=True, physicsClientId=c)
            self.body_of[f.name] = bid
            self.furniture_top[f.name] = p.getAABB(bid, physicsClientId=c)[1][2]
        for name, area in w.containers.items():
            self._make_drawer(name, area, opened=name in w.opened)
        for name, area in w.trays.items():
            self._make_tray(name, area)
        for t in w.things.values():
            r, h, rgba = SHAPES.get(t.kind, DEFAULT_SHAPE)
            self.radius[t.name], self.height[t.name] = r, h
            if t.on in w.containers:
                d = self.drawers[t.on]
                used = sum(1 for o in w.things.values() if o.on == t.on and o.name in self.body_of)
                x, y, z = self._in_drawer_spot(d, used)
            else:
                spot = self._free_spot(t.on, None, r)
                if spot is None:
                    raise HtnError(f"no room for {t.name} on the table of {t.on}")
                x, y, z = spot
            self.body_of[t.name] = self._make_object(r, h, rgba, x, y, z + h / 2 + 0.002)
        start = w.place(w.robot_at)
        self.base = [start.x, start.y, start.theta]
        with quiet_fds():
            self.husky = p.loadURDF("husky/husky.urdf", [start.x, start.y, BASE_Z],
                                    _yaw_quat(p, start.theta), useFixedBase=True, physicsClientId=c)
        self.arm_body = {}
        self.q_cmd: dict[str, list] = {}
        self.f_cmd: dict[str, float] = {}
        self.arm_grip: dict[str, Optional[int]] = {}
        for arm in self.ARMS:
            body = p.loadURDF("franka_panda/panda.urdf", self._arm_mount(arm),
                              _yaw_quat(p, start.theta), useFixedBase=True, physicsClientId=c)
            self.arm_body[arm], self.arm_held[arm], self.arm_grip[arm] = body, None, None
            self._command(arm, ARM_HOMES[arm])
            self._set_fingers_of(arm, 0.04)
        bodies = [self.husky, *self.arm_body.values()]
        for a in bodies:
            for b in bodies:
                if a < b:
                    for j in range(-1, p.getNumJoints(a, physicsClientId=c)):
                        for k in range(-1, p.getNumJoints(b, physicsClientId=c)):
                            p.setCollisionFilterPair(a, b, j, k, 0, physicsClientId=c)
        self._select("left")
        self.body_of[w.robot] = self.husky
        self._settle(0.5)

    def _frame(self, area: str) -> tuple[float, float, float]:
        pl = self.world.places[area]
        return pl.x, pl.y, pl.theta

    def _to_world(self, area: str, u: float, v: float) -> tuple[float, float]:
        x, y, yaw = self._frame(area)
        return (x + u * math.cos(yaw) - v * math.sin(yaw),
                y + u * math.sin(yaw) + v * math.cos(yaw))

    def _to_area(self, area: str, x: float, y: float) -> tuple[float, float]:
        ax, ay, yaw = self._frame(area)
        dx, dy = x - ax, y - ay
        return (dx * math.cos(yaw) + dy * math.sin(yaw), -dx * math.sin(yaw) + dy * math.cos(yaw))

    def _boxes(self, parts, mass: float, pos, yaw: float, rgba) -> int:
        """A rigid body made of boxes: parts are (half extents, offset) in the body frame."""
        p, c = self.p, self.cid
        n = len(parts)
        col = p.createCollisionShapeArray([p.GEOM_BOX] * n, halfExtents=[h for h, _ in parts],
                                          collisionFramePositions=[o for _, o in parts],
                                          physicsClientId=c)
        vis = p.createVisualShapeArray([p.GEOM_BOX] * n, halfExtents=[h for h, _ in parts],
                                       visualFramePositions=[o for _, o in parts],
                                       rgbaColors=[rgba] * n, physicsClientId=c)
        return p.createMultiBody(mass, col, vis, pos, _yaw_quat(p, yaw), physicsClientId=c)

    def _open_box(self, hu: float, hv: float, hz: float, wall: float = 0.006) -> list:
        """Bottom and four walls of an open-top box (body frame: x = u, y = v)."""
        return [((hu, hv, wall / 2), (0, 0, wall / 2)),
                ((wall / 2, hv, hz), (hu - wall / 2, 0, hz)),
                ((wall / 2, hv, hz), (-hu + wall / 2, 0, hz)),
                ((hu, wall / 2, hz), (0, hv - wall / 2, hz)),
                ((hu, wall / 2, hz), (0, -hv + wall / 2, hz))]

    def _make_drawer(self, name: str, area: str, opened: bool) -> None:
        top = self.furniture_top[area]
        yaw = self._frame(area)[2]
        hu, hv, hz = DRAWER_HALF
        x, y = self._to_world(area, DRAWER_U, DRAWER_V)
        # the housing: top, sides and back, open towards the robot
        t = 0.01
        H = HOUSING_HEIGHT / 2
        housing = self._boxes([((hu + t, hv + 2 * t, t / 2), (0, 0, 2 * H - t / 2)),
                               ((hu + t, t / 2, H), (0, hv + 1.5 * t, H)),
                               ((hu + t, t / 2, H), (0, -hv - 1.5 * t, H)),
                               ((t / 2, hv + 2 * t, H), (hu + 1.5 * t, 0, H))],
                              0.0, [x, y, top], yaw, (0.55, 0.4, 0.25, 1))
        body = self._boxes(self._open_box(hu, hv, hz), 0.0, [x, y, top + 0.001], yaw,
                           (0.75, 0.6, 0.4, 1))
        d = Drawer(name, area, body)
        self.drawers[name] = d
        self.body_of[name] = body
        self.body_of[f"{name}-housing"] = housing
        if opened:
            self._slide_drawer(d, DRAWER_OPEN, [])

    def _make_tray(self, name: str, area: str) -> None:
        top = self.furniture_top[area]
        yaw = self._frame(area)[2]
        hu, hv, hz = TRAY_HALF
        x, y = self._to_world(area, TRAY_U, 0.0)
        bid = self._boxes(self._open_box(hu, hv, hz / 2, wall=0.008), 0.6, [x, y, top + 0.002], yaw,
                          (0.3, 0.3, 0.3, 1))
        self.p.changeDynamics(bid, -1, lateralFriction=1.0, physicsClientId=self.cid)
        self.trays[name] = bid
        self.body_of[name] = bid

    def _make_object(self, r: float, h: float, rgba, x: float, y: float, z: float) -> int:
        p, c = self.p, self.cid
        col = p.createCollisionShape(p.GEOM_CYLINDER, radius=r, height=h, physicsClientId=c)
        vis = p.createVisualShape(p.GEOM_CYLINDER, radius=r, length=h, rgbaColor=rgba,
                                  physicsClientId=c)
        bid = p.createMultiBody(0.1, col, vis, [x, y, z], physicsClientId=c)
        p.changeDynamics(bid, -1, lateralFriction=1.0, physicsClientId=c)
        return bid

    # ------------------------------------------------------------ places for things
    def _in_drawer_spot(self, d: Drawer, slot: int) -> tuple[float, float, float]:
        u = DRAWER_U - d.out + (0.05 if slot % 4 >= 2 else -0.05)
        v = DRAWER_V + (0.05 if slot % 2 else -0.05)
        x, y = self._to_world(d.area, u, v)
        return x, y, self.furniture_top[d.area] + 0.007

    def _footprints(self, area: str, skip=()) -> list[tuple[float, float, float]]:
        """Discs (u, v, radius) of what occupies the area's table."""
        out = []
        for name, d in self.drawers.items():
            if d.area == area:   # the housing and the drawer pulled out
                for u in (DRAWER_U, DRAWER_U - DRAWER_OPEN):
                    out.append((u, DRAWER_V, 0.17))
        for name, bid in self.trays.items():
            pos = self._pos(bid)
            if self._on_table(bid, area):
                out += self._tray_discs(*self._to_area(area, pos[0], pos[1]))
        for t in self.world.things:
            if t in self.body_of and t not in skip and t not in self.arm_held.values():
                pos = self._body_pos(t)
                u, v = self._to_area(area, pos[0], pos[1])
                if 0.4 < u < 1.7 and abs(v) < 0.9:
                    out.append((u, v, self.radius[t]))
        return out

    def _free_spot(self, area: str, arm: Optional[str], radius: float, skip=()):
        """A free, reachable spot on the area's table: near the front, on the
        arm's side. Returns world (x, y, table top) or None."""
        taken = self._footprints(area, skip)
        side = SIDE.get(arm, 0.0)
        spots = sorted(((u, v) for u in ROWS for v in SPOT_VS),
                       key=lambda s: (abs(s[1] - 0.15 * side) + 0.8 * (s[0] - ROWS[0])))
        top = self.furniture_top[area]
        for u, v in spots:
            if all(math.hypot(u - tu, v - tv) > radius + tr + 0.04 for tu, tv, tr in taken):
                x, y = self._to_world(area, u, v)
                if arm is None or self._reachable(arm, [x, y, top + 0.2]):
                    return x, y, top
        return None

    def _reachable(self, arm: str, pos) -> bool:
        with self._using(arm):
            return self._ik(pos) is not None

    # ------------------------------------------------------------ arms, one at a time
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
        """Run the one-arm helpers of :class:`PyBulletRobot` on ``arm``."""
        previous = self.active
        self._select(arm)
        try:
            yield
        finally:
            self.arm_held[arm], self.arm_grip[arm] = self.held, self._grip_constraint
            self._select(previous)

    @property
    def carrying(self) -> Optional[str]:
        held = [o for o in self.arm_held.values() if o]
        return held[0] if len(held) == 1 else None

    @carrying.setter
    def carrying(self, value) -> None:   # the base class sets it; here it follows the hands
        pass

    def _pick_arm(self, arm: Optional[str]) -> Optional[str]:
        if arm in self.ARMS:
            return arm
        return next((a for a in self.ARMS if self.arm_held[a] is None), None)

    def _rest_pose(self) -> None:
        """The selected arm: holding something, close to its side; else tucked."""
        if self.held is None:
            self._move_arm(ARM_HOMES[self.active], 0.7)
            return
        x, y, yaw = self.base
        side = SIDE[self.active]
        mx, my, _ = self._arm_mount(self.active)
        lx, ly = -math.sin(yaw) * side, math.cos(yaw) * side
        fx, fy = math.cos(yaw), math.sin(yaw)
        if not self._reach([mx + 0.2 * fx + 0.25 * lx, my + 0.2 * fy + 0.25 * ly, 0.95], 0.7):
            self._move_arm(ARM_HOMES[self.active], 0.7)
        self._step(12)

    _carry_pose = _rest_pose

    def _move_arms(self, goals: dict, seconds: float) -> None:
        """Both arms at once, in joint space."""
        p, c = self.p, self.cid
        starts = {a: [p.getJointState(self.arm_body[a], j, physicsClientId=c)[0]
                      for j in ARM_JOINTS] for a in goals}
        n = max(1, int(seconds / DT))
        for i in range(1, n + 1):
            k = i / n
            for a, q in goals.items():
                self._command(a, [s + (g - s) * k for s, g in zip(starts[a], q)])
            self._step()

    def _command(self, arm: str, q) -> None:
        """Set an arm's joints; :meth:`_step` keeps them there (kinematic arms)."""
        self.q_cmd[arm] = list(q)
        for j, v in zip(ARM_JOINTS, q):
            self.p.resetJointState(self.arm_body[arm], j, v, physicsClientId=self.cid)

    def _move_arm(self, q_goal, seconds: float = 1.0) -> None:
        self._move_arms({self.active: q_goal}, seconds)

    def _set_fingers(self, width: float) -> None:
        self._set_fingers_of(self.active, width)

    def _ik_for(self, arm: str, pos) -> Optional[list[float]]:
        with self._using(arm):
            return self._ik(pos)

    # ------------------------------------------------------------ clock and base
    def _step(self, n: int = 1) -> None:
        p, c = self.p, self.cid
        for _ in range(n):
            if self.hold_tray is not None:
                ee_pos, ee_orn = p.getLinkState(self.arm_body["left"], EE_LINK,
                                                physicsClientId=c)[4:6]
                pos, orn = p.multiplyTransforms(ee_pos, ee_orn, *self.hold_tray.rel)
                p.changeConstraint(self.hold_tray.constraint, jointChildPivot=pos,
                                   jointChildFrameOrientation=orn, maxForce=300,
                                   physicsClientId=c)
            for arm, body in self.arm_body.items():   # nothing pushes the arms around
                for j, v in zip(ARM_JOINTS, self.q_cmd[arm]):
                    p.resetJointState(body, j, v, physicsClientId=c)
                for j in FINGERS:
                    p.resetJointState(body, j, self.f_cmd[arm], physicsClientId=c)
            p.stepSimulation(physicsClientId=c)
        self.sim_time += n * DT

    def _mounted(self) -> list:
        return [(body, self._arm_mount(arm)) for arm, body in self.arm_body.items()]

    def _speeds(self) -> tuple[float, float]:
        """Slower with the tray, so what stands on it does not slide."""
        return (TRAY_BASE_SPEED, TRAY_TURN_SPEED) if self.hold_tray else (BASE_SPEED, TURN_SPEED)

    @staticmethod
    def _ramp(k: float) -> float:
        """A smooth (cosine) speed profile: no jerk at start and stop."""
        return 0.5 - 0.5 * math.cos(math.pi * k)

    def _carried_bodies(self) -> set:
        out = {self.body_of[o] for o in self.arm_held.values() if o}
        if self.hold_tray is not None:
            tray = self.trays[self.hold_tray.tray]
            out.add(tray)
            out |= {self.body_of[o] for o in self.hold_tray.riders}
        return out

    def _base_contacts(self) -> list[str]:
        p, c = self.p, self.cid
        own = {self.plane, self.husky, *self.arm_body.values()} | self._carried_bodies()
        names = []
        for body in (self.husky, *self.arm_body.values()):
            for cp in p.getContactPoints(bodyA=body, physicsClientId=c):
                if cp[2] not in own:
                    names.append(self.bodies_named.get(cp[2], str(cp[2])))
        return sorted(set(names))

    # ------------------------------------------------------------ world queries
    def _pos(self, body: int) -> np.ndarray:
        return np.array(self.p.getBasePositionAndOrientation(body, physicsClientId=self.cid)[0])

    def _touching(self, a: int, b: int) -> bool:
        return bool(self.p.getContactPoints(bodyA=a, bodyB=b, physicsClientId=self.cid))

    def _on_table(self, body: int, area: str) -> bool:
        table = self.body_of.get(area)
        if table is None or area not in self.furniture_top:
            return False
        top = self.furniture_top[area]
        return any(cp[5][2] >= top - 0.02 for cp in self.p.getContactPoints(
            bodyA=body, bodyB=table, physicsClientId=self.cid))

    def _on_tray(self, tray: str) -> list[str]:
        bid = self.trays[tray]
        tp = self._pos(bid)
        out = []
        for t in self.world.things:
            if t in self.arm_held.values():
                continue
            pos = self._body_pos(t)
            if self._touching(self.body_of[t], bid) and pos[2] > tp[2] and \
                    math.hypot(*(pos[:2] - tp[:2])) < 0.25:
                out.append(t)
        return out

    def _in_drawer(self, obj: str, d: Drawer) -> bool:
        pos = self._body_pos(obj)
        dp = self._pos(d.body)
        u, v = self._to_area(d.area, pos[0], pos[1])
        du, dv = self._to_area(d.area, dp[0], dp[1])
        return (abs(u - du) < DRAWER_HALF[0] and abs(v - dv) < DRAWER_HALF[1]
                and dp[2] <= pos[2] < dp[2] + 2 * DRAWER_HALF[2] + 0.05
                and obj not in self.arm_held.values())

    def _container_of(self, obj: str) -> Optional[Drawer]:
        return next((d for d in self.drawers.values() if self._in_drawer(obj, d)), None)

    def _area_of(self, where: str) -> str:
        if where in self.drawers:
            return self.drawers[where].area
        return where

    def _look_target(self, area: str) -> list[float]:
        x, y = self._to_world(area, 0.85, 0.0)
        return [x, y, self.furniture_top.get(area, 0.6)]

    # ------------------------------------------------------------ skills
    def move_base(self, place: str) -> SkillResult:
        """Back away from the table, drive to a pose in front of the goal's
        table, turn to face it and drive up to it: turning in place next to a
        table (or an open drawer) would sweep the arms through it."""
        goal = self.world.place(place)
        fraction = self._nav_fault(place)
        x, y, yaw = self.base
        here = next((a for a, pl in self.world.places.items()
                     if math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE), None)
        if math.hypot(goal.x - x, goal.y - y) > POSE_TOLERANCE:
            if here in self.furniture_top and \
                    not self._drive(x - DOCK * math.cos(yaw), y - DOCK * math.sin(yaw)):
                return SkillResult(True, "bumped into something while backing away")
            dock = DOCK if place in self.furniture_top else 0.0
            px, py = goal.x - dock * math.cos(goal.theta), goal.y - dock * math.sin(goal.theta)
            if not self._face(px, py):
                return SkillResult(True, "bumped into something while turning")
            if not self._drive(px, py, fraction):
                return SkillResult(True, "bumped into something while driving")
            if fraction < 1.0:
                return SkillResult(True, f"stopped at {self.base[0]:.2f} {self.base[1]:.2f}")
        if not self._turn_to(goal.theta):
            return SkillResult(True, "bumped into something while turning")
        if math.hypot(goal.x - self.base[0], goal.y - self.base[1]) > 1e-4 and \
                not self._drive(goal.x, goal.y):
            return SkillResult(True, "bumped into something while driving up to the table")
        self._step(12)
        return SkillResult(True, f"stopped at {self.base[0]:.2f} {self.base[1]:.2f}")

    def detect_object(self, obj: str, where: str) -> SkillResult:
        """Look at the area's table. An object in a closed drawer cannot be
        seen: the robot sees the drawer it is in (which it knows)."""
        self.detections.pop(obj, None)
        self.believed_in.pop(obj, None)
        if obj not in self.body_of:
            return SkillResult(False, f"unknown object {obj}")
        area = self._area_of(where)
        target = self._look_target(area)
        pixels = self._look(obj, target)
        if pixels >= 5:
            return SkillResult(True, f"{obj} seen ({pixels} px)", {"pixels": pixels})
        for d in self.drawers.values():
            if d.area == area and d.out < 0.02 and self._in_drawer(obj, d) and \
                    self._visible_pixels(f"{d.name}-housing", target) >= 5:
                self.believed_in[obj] = d.name
                return SkillResult(True, f"{obj} is in the closed {d.name}")
        return SkillResult(True, f"{obj} not seen")

    def grasp(self, obj: str, where: str, arm: Optional[str] = None) -> SkillResult:
        """Top grasp at the detected pose: open, descend, close, lift, hold at the side."""
        arm = self._pick_arm(arm)
        if arm is None:
            return SkillResult(False, "both hands are full")
        if self.arm_held[arm] is not None:
            return SkillResult(False, f"the {arm} hand already holds {self.arm_held[arm]}")
        if obj not in self.detections:        # e.g. in a drawer, or on a retry: look first
            self.detect_object(obj, where)
        guess = self.detections.get(obj)
        if guess is None:
            return SkillResult(True, f"no detection of {obj} to grasp")
        if self.faults.moved and obj not in self._moved and self.rng.random() < self.faults.moved:
            self._moved.add(obj)   # somebody takes it away once, just before the grasp
            self._move_object_elsewhere(obj, self._area_of(where))
        with self._using(arm):
            return self._top_grasp(obj, guess)

    def _move_object_elsewhere(self, obj: str, area: str) -> None:
        """Fault: somebody takes the object to a free spot on another table."""
        for other in sorted(a for a in self.furniture_top if a != area):
            spot = self._free_spot(other, None, self.radius[obj], skip=(obj,))
            if spot is not None:
                x, y, z = spot
                self._inject("moved", f"{obj} taken from {area} to {other}")
                self.p.resetBasePositionAndOrientation(
                    self.body_of[obj], [x, y, z + self.height[obj] / 2 + 0.002], [0, 0, 0, 1],
                    physicsClientId=self.cid)
                self._settle(0.2)
                return

    def _top_grasp(self, obj: str, guess) -> SkillResult:
        gx, gy, gz = guess
        r = self.radius[obj]
        clear = gz + self.height[obj] / 2 + 0.12
        self._set_fingers(0.04)
        if not self._reach([gx, gy, clear], 0.8) or not self._reach([gx, gy, gz + 0.01], 0.6):
            self._rest_pose()
            return SkillResult(False, f"{obj} is out of the {self.active} arm's reach")
        for w_ in np.linspace(0.04, max(0.004, r - 0.005), 12):
            self._set_fingers(float(w_))
            self._step(2)
        body = self.body_of[obj]
        if self._fingers_touch(body):
            self.held = obj
            self._attach(body)
        if self.held and self.faults.slip and self.rng.random() < self.faults.slip:
            self._reach([gx, gy, gz + 0.03], 0.2)
            self._inject("slip", f"{obj} slips out of the {self.active} gripper")
            self._release()
            self._set_fingers(0.04)
            self._settle(0.3)
        lifted = self._reach([gx, gy, clear], 0.5)
        self.detections.pop(obj, None)
        self.believed_in.pop(obj, None)
        self._rest_pose()
        if not lifted:
            return SkillResult(False, "could not lift the arm")
        return SkillResult(True, f"{self.active} gripper closed")

    def _put_down(self, obj: str, x: float, y: float, z: float, what: str) -> SkillResult:
        """Lower what the selected hand holds onto (x, y) of a surface at z, let go."""
        h = self.height[obj]
        if not self._reach([x, y, z + h / 2 + 0.12], 0.8):
            return SkillResult(False, f"{what} is out of the {self.active} arm's reach")
        self._reach([x, y, z + h / 2 + 0.012], 0.6)
        self._release()
        self._set_fingers(0.04)
        self._settle(0.3)
        self._reach([x, y, z + h / 2 + 0.12], 0.5)
        self._rest_pose()
        return SkillResult(True, f"{self.active} gripper opened over {what}")

    def place_object(self, obj: str, where: str, arm: Optional[str] = None) -> SkillResult:
        arm = arm if arm in self.ARMS else next(
            (a for a in self.ARMS if self.arm_held[a] == obj), None)
        if arm is None or self.arm_held[arm] != obj:
            return SkillResult(True, f"{obj} is not in the {arm or 'robot'}'s hand")
        if where not in self.furniture_top:
            return SkillResult(False, f"no table at {where}")
        spot = self._free_spot(where, arm, self.radius[obj])
        if spot is None:
            return SkillResult(False, f"no free spot within reach on the table of {where}")
        with self._using(arm):
            return self._put_down(obj, *spot, what=f"the table of {where}")

    # ---- the drawer
    def _slide_drawer(self, d: Drawer, out: float, contents: list) -> None:
        """Move the drawer (and what lies in it) to ``out`` metres pulled out."""
        p, c = self.p, self.cid
        x, y, yaw = self._frame(d.area)
        du = -(out - d.out)
        dx, dy = du * math.cos(yaw), du * math.sin(yaw)
        for body in [d.body] + contents:
            pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=c)
            p.resetBasePositionAndOrientation(body, [pos[0] + dx, pos[1] + dy, pos[2]], orn,
                                              physicsClientId=c)
            if body != d.body:
                p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=c)
        d.out = out

    def _pull(self, d: Drawer, goal: float, verb: str) -> SkillResult:
        arm = self._pick_arm(None)
        if arm is None:
            return SkillResult(False, f"both hands are full: {d.name} stays as it is")
        top = self.furniture_top[d.area]
        grip_z = top + 2 * DRAWER_HALF[2] - 0.01
        def handle(out):   # the top of the drawer's front wall
            return [*self._to_world(d.area, DRAWER_U - out - DRAWER_HALF[0] + 0.003, DRAWER_V), grip_z]
        contents = [self.body_of[t] for t in self.world.things
                    if t in self.body_of and self._in_drawer(t, d)]
        with self._using(arm):
            self._set_fingers(0.04)
            start = handle(d.out)
            if not self._reach([start[0], start[1], grip_z + 0.1], 0.8) or \
                    not self._reach(start, 0.5):
                self._rest_pose()
                return SkillResult(False, f"the handle of {d.name} is out of the {arm} arm's reach")
            self._set_fingers(0.002)
            self._step(6)
            q0 = self._arm_q()
            q1 = self._ik(handle(goal))
            if q1 is None:
                self._rest_pose()
                return SkillResult(False, f"the {arm} arm cannot reach where {d.name} is {verb}")
            n = max(1, int(abs(goal - d.out) / (0.2 * DT)))
            for i in range(1, n + 1):
                k = i / n
                self._command(arm, [a + (b - a) * k for a, b in zip(q0, q1)])
                # the drawer follows the hand along its rail
                ee_u, _ = self._to_area(d.area, *self._ee()[:2])
                out = min(DRAWER_OPEN, max(0.0, DRAWER_U - DRAWER_HALF[0] + 0.003 - ee_u))
                self._slide_drawer(d, out, contents)
                self._step()
            self._set_fingers(0.04)
            end = self._ee()
            self._reach([end[0], end[1], grip_z + 0.1], 0.4)
            self._rest_pose()
        return SkillResult(True, f"{d.name} {verb} by the {arm} arm ({d.out:.2f} m out)")

    def open_container(self, container: str) -> SkillResult:
        d = self.drawers.get(container)
        if d is None:
            return SkillResult(False, f"no drawer {container}")
        return self._pull(d, DRAWER_OPEN, "opened")

    def close_container(self, container: str) -> SkillResult:
        d = self.drawers.get(container)
        if d is None:
            return SkillResult(False, f"no drawer {container}")
        return self._pull(d, 0.0, "closed")

    # ---- the tray
    def put_on_tray(self, obj: str, tray: str, arm: Optional[str] = None) -> SkillResult:
        arm = arm if arm in self.ARMS else next(
            (a for a in self.ARMS if self.arm_held[a] == obj), None)
        if tray not in self.trays:
            return SkillResult(False, f"no tray {tray}")
        if arm is None or self.arm_held[arm] != obj:
            return SkillResult(True, f"{obj} is not in the {arm or 'robot'}'s hand")
        p, c = self.p, self.cid
        tpos, torn = p.getBasePositionAndOrientation(self.trays[tray], physicsClientId=c)
        on = [self._body_pos(t) for t in self._on_tray(tray)]
        for du, dv in sorted(TRAY_SPOTS, key=lambda s: -s[1] * SIDE[arm]):
            x, y = p.multiplyTransforms(tpos, torn, [du, dv, 0], [0, 0, 0, 1])[0][:2]
            if all(math.hypot(x - o[0], y - o[1]) > 0.07 for o in on) and \
                    self._reachable(arm, [x, y, tpos[2] + 0.2]):
                with self._using(arm):
                    return self._put_down(obj, x, y, tpos[2] + 0.008, f"{tray}")
        return SkillResult(False, f"no free spot on {tray} within the {arm} arm's reach")

    def take_from_tray(self, obj: str, tray: str, arm: Optional[str] = None) -> SkillResult:
        arm = self._pick_arm(arm)
        if arm is None or self.arm_held[arm] is not None:
            return SkillResult(False, f"the {arm or 'robot'}'s hand is not free")
        if tray not in self.trays or obj not in self.body_of:
            return SkillResult(False, f"unknown tray or object {tray}/{obj}")
        if self._visible_pixels(obj, list(self._body_pos(tray))) < 5:
            return SkillResult(True, f"{obj} is not seen on {tray}")
        with self._using(arm):
            return self._top_grasp(obj, self._noisy_pos(obj))

    def _rims(self, pos, orn) -> dict:
        """Where each hand holds the tray (posed at pos, orn): the middle of its side rim."""
        hv = TRAY_HALF[1] - 0.004
        z = TRAY_HALF[2] - 0.01
        return {a: list(self.p.multiplyTransforms(pos, orn, [0, SIDE[a] * hv, z],
                                                  [0, 0, 0, 1])[0]) for a in self.ARMS}

    def lift_tray(self, tray: str) -> SkillResult:
        if tray not in self.trays:
            return SkillResult(False, f"no tray {tray}")
        if any(self.arm_held.values()) or self.hold_tray is not None:
            return SkillResult(False, "the tray needs both hands free")
        p, c = self.p, self.cid
        bid = self.trays[tray]
        pos, orn = p.getBasePositionAndOrientation(bid, physicsClientId=c)
        rims = self._rims(pos, orn)
        above = {a: [r[0], r[1], r[2] + 0.1] for a, r in rims.items()}
        lifted = {a: [r[0], r[1], r[2] + 0.12] for a, r in rims.items()}
        for a in self.ARMS:
            self._set_fingers_of(a, 0.04)
        for stage in (above, rims):
            qs = {a: self._ik_for(a, stage[a]) for a in self.ARMS}
            if any(q is None for q in qs.values()):
                self._home_both()
                return SkillResult(False, f"{tray} is out of reach of both arms")
            self._move_arms(qs, 0.8)
        self._hands_touch_tray(bid, False)   # they hold its rims: no contact forces
        for a in self.ARMS:
            self._set_fingers_of(a, 0.004)
        self._step(6)
        ee_pos, ee_orn = p.getLinkState(self.arm_body["left"], EE_LINK, physicsClientId=c)[4:6]
        inv = p.invertTransform(ee_pos, ee_orn)
        rel = p.multiplyTransforms(inv[0], inv[1], pos, orn)
        cid = p.createConstraint(bid, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0], pos,
                                 childFrameOrientation=orn, physicsClientId=c)
        self.hold_tray = Hold(tray, cid, rel, tuple(self._on_tray(tray)))
        goals = {a: self._ik_for(a, lifted[a]) for a in self.ARMS}
        if any(q is None for q in goals.values()):
            self._let_go_of_tray()
            return SkillResult(False, f"the arms cannot lift {tray}")
        self._move_arms(goals, 1.0)
        self._step(24)
        return SkillResult(True, f"{tray} lifted with both hands")

    def lower_tray(self, tray: str, where: str) -> SkillResult:
        if self.hold_tray is None or self.hold_tray.tray != tray:
            return SkillResult(True, f"{tray} is not in the hands")
        if where not in self.furniture_top:
            return SkillResult(False, f"no table at {where}")
        p = self.p
        top = self.furniture_top[where]
        yaw = self.base[2]
        taken = self._footprints(where, skip=self._on_tray(tray))
        for v in (0.0, -0.1, 0.1, -0.2, 0.2, -0.3, 0.3):
            if any(math.hypot(u - tu, w - tv) < tr + 0.1
                   for u, w, _ in self._tray_discs(TRAY_U, v) for tu, tv, tr in taken):
                continue
            x, y = self._to_world(where, TRAY_U, v)
            pos, orn = [x, y, top + 0.004], _yaw_quat(p, yaw)
            rims = self._rims(pos, orn)
            ee_goal = p.multiplyTransforms(pos, orn, *p.invertTransform(*self.hold_tray.rel))[0]
            left = self._ik_for("left", ee_goal)
            right = self._ik_for("right", [*rims["right"][:2], ee_goal[2]])
            if left is not None and right is not None:
                break
        else:
            return SkillResult(False, f"no free place for {tray} within reach on {where}")
        self._move_arms({"left": left, "right": right}, 1.2)
        self._let_go_of_tray()
        self._home_both()
        return SkillResult(True, f"{tray} lowered onto {where}")

    def _tray_discs(self, u: float, v: float) -> list[tuple[float, float, float]]:
        """Four discs (u, v, radius) covering a tray centred at (u, v) of an area."""
        return [(u + du, v + dv, 0.12) for du in (-0.07, 0.07) for dv in (-0.09, 0.09)]

    def _hands_touch_tray(self, tray_body: int, touch: bool) -> None:
        for a in self.ARMS:
            for link in (*FINGERS, 8, 7, 6):
                self.p.setCollisionFilterPair(self.arm_body[a], tray_body, link, -1, int(touch),
                                              physicsClientId=self.cid)

    def _let_go_of_tray(self) -> None:
        """Release the tray where it is: let it settle, open and raise both hands."""
        bid = self.trays[self.hold_tray.tray]
        self.p.removeConstraint(self.hold_tray.constraint, physicsClientId=self.cid)
        self.hold_tray = None
        self._settle(0.3)
        for a in self.ARMS:
            self._set_fingers_of(a, 0.04)
        ups = {a: self._ik_for(a, [*self._ee_of(a)[:2], self._ee_of(a)[2] + 0.1]) for a in self.ARMS}
        self._move_arms({a: q for a, q in ups.items() if q is not None}, 0.4)
        self._hands_touch_tray(bid, True)

    def _set_fingers_of(self, arm: str, width: float) -> None:
        self.f_cmd[arm] = width
        for j in FINGERS:
            self.p.resetJointState(self.arm_body[arm], j, width, physicsClientId=self.cid)

    def _ee_of(self, arm: str) -> np.ndarray:
        return np.array(self.p.getLinkState(self.arm_body[arm], EE_LINK,
                                            physicsClientId=self.cid)[4])

    def _home_both(self) -> None:
        self._move_arms({a: ARM_HOMES[a] for a in self.ARMS}, 0.8)

    # ------------------------------------------------------------ checks (monitors)
    def check_in_gripper(self, obj: str) -> Check:
        if obj not in self.body_of:
            return Check(False, f"no object {obj}")
        arm = next((a for a in self.ARMS if self.arm_held[a] == obj), None)
        if arm is None:
            return Check(False, f"{obj} is in neither hand")
        pos = self._body_pos(obj)
        d = float(np.linalg.norm(pos - self._ee_of(arm)))
        lifted = pos[2] > max(self.furniture_top.values(), default=0.0) + 0.1
        ok = d < 0.06 and lifted and self.arm_grip[arm] is not None
        return Check(ok, f"{obj} is {d:.3f} m from the {arm} gripper"
                     + ("" if lifted else ", not lifted"))

    def check_on(self, obj: str, where: str) -> Check:
        if obj not in self.body_of:
            return Check(False, f"no object {obj}")
        body = self.body_of[obj]
        where_now = next((a for a in self.furniture_top if self._on_table(body, a)), None)
        ok = where_now == where and obj not in self.arm_held.values()
        return Check(ok, f"{obj} rests on {('the table of ' + where_now) if where_now else 'nothing'}")

    def check_detection(self, obj: str) -> Check:
        if obj in self.believed_in:
            d = self.drawers[self.believed_in[obj]]
            ok = self._in_drawer(obj, d)
            return Check(ok, f"{obj} {'is' if ok else 'is not'} in {d.name}")
        return super().check_detection(obj)

    def check_opened(self, container: str, opened: bool) -> Check:
        d = self.drawers.get(container)
        if d is None:
            return Check(False, f"no drawer {container}")
        ok = d.out >= 0.8 * DRAWER_OPEN if opened else d.out <= 0.02
        return Check(ok, f"{container} is {d.out:.2f} m out")

    def check_on_tray(self, obj: str, tray: str) -> Check:
        if tray not in self.trays or obj not in self.body_of:
            return Check(False, f"unknown tray or object {tray}/{obj}")
        ok = obj in self._on_tray(tray)
        return Check(ok, f"{obj} {'rests' if ok else 'does not rest'} on {tray}")

    def check_tray_carried(self, tray: str, carried: bool, where: Optional[str] = None) -> Check:
        if tray not in self.trays:
            return Check(False, f"no tray {tray}")
        bid = self.trays[tray]
        z = self._pos(bid)[2]
        if carried:
            top = max(self.furniture_top.values(), default=0.0)
            ok = self.hold_tray is not None and self.hold_tray.tray == tray and z > top + 0.06
            return Check(ok, f"{tray} held {z - top:.2f} m above the table tops")
        ok = self.hold_tray is None and self._on_table(bid, where)
        return Check(ok, f"{tray} rests on " + (f"the table of {where}" if ok else "something else"))

    # ------------------------------------------------------------ state estimation
    def observe(self) -> list[tuple[str, tuple]]:
        facts: list[tuple[str, tuple]] = []
        x, y, yaw = self.base
        for pl in self.world.places.values():
            if math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE and \
                    abs(_angle_diff(pl.theta, yaw)) <= YAW_TOLERANCE:
                facts.append(("robot-at", (pl.name,)))
                break
        else:   # stopped on the way: a new area where the robot stands
            facts += [("area", ("here", round(x, 3), round(y, 3))), ("robot-at", ("here",))]
        for arm in self.ARMS:
            obj = self.arm_held[arm]
            if obj is not None and self.check_in_gripper(obj).ok:
                facts.append(("holding", (arm, obj)))
            elif self.hold_tray is None:
                facts.append(("free", (arm,)))
        for t in self.world.things:
            body = self.body_of[t]
            area = next((a for a in self.furniture_top if self._on_table(body, a)), None)
            d = self._container_of(t)
            if area is not None:
                facts.append(("at", (t, area)))
            elif d is not None:
                facts.append(("in", (t, d.name)))
        for name, d in self.drawers.items():
            if d.out >= 0.8 * DRAWER_OPEN:
                facts.append(("opened", (name,)))
        for tray, bid in self.trays.items():
            if self.hold_tray is not None and self.hold_tray.tray == tray:
                facts.append(("carrying-tray", (tray,)))
            else:
                area = next((a for a in self.furniture_top if self._on_table(bid, a)), None)
                if area is not None:
                    facts.append(("tray", (tray, area)))
            facts += [("on-tray", (t, tray)) for t in self._on_tray(tray)]
        return facts
