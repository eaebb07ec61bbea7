"""The kitchen in PyBullet: a Husky base with two Franka Panda arms, tables,
a drawer and a tray, for the pick-and-place domain (``domains/kitchen.jshop``).

The world comes from a kitchen problem's initial state
(:func:`htn.robot.world.kitchen_world_from_state`): each working area gets a table
in front of its base pose. Objects are cylinders sized by kind (bowl, cup,
spoon, ...). The robot shares the domestic robot's parts (base, arm and
gripper, perception; one arm at a time) and adds two more: drawers
(:mod:`~htn.robot.drawer`) and trays (:mod:`~htn.robot.tray`).

Motion is kinematic and everything else is physics: objects rest on tables,
in the drawer and on the tray, and ride on the tray by friction while it is
carried. Geometry is in each area's frame: ``u`` forward from the base pose
towards the table, ``v`` to the robot's left.
"""
from __future__ import annotations

import math
from typing import Optional


from htn.jshop.language.errors import HtnError

from .arm import ARM_JOINTS, FINGERS
from .base import BASE_SPEED, POSE_TOLERANCE, TURN_SPEED
from .drawer import DRAWER_OPEN, Drawers
from .drive import XY_TOL
from .interface import Check, SkillResult, check, skill
from .physics import quiet_fds, yaw_quat
from .pybullet_sim import PyBulletRobot
from .table_spots import TableSpots
from .tray import Trays
from .two_arms import ARM_HOMES, TwoArms

SHAPES = {   # kind -> (radius, height, colour)
    "bowl": (0.035, 0.06, (0.95, 0.95, 0.9, 1)),
    "cup": (0.03, 0.09, (0.2, 0.4, 0.9, 1)),
    "spoon": (0.02, 0.08, (0.6, 0.6, 0.65, 1)),
}
DEFAULT_SHAPE = (0.033, 0.12, (0.9, 0.2, 0.1, 1))
TRAY_BASE_SPEED, TRAY_TURN_SPEED = 0.35, 0.6
TRAY_ACCEL, TRAY_TURN_ACCEL = 0.3, 0.6     # m/s^2, rad/s^2
ARM_AND_FINGERS = [*ARM_JOINTS, *FINGERS]
DOCK = 0.35                         # backing away from a table before turning


class KitchenRobot(Drawers, Trays, TableSpots, TwoArms, PyBulletRobot):
    """The simulated two-armed kitchen robot; ``gui=True`` opens a window."""

    CAMERA_PIXELS = (160, 120)   # finer than the domestic robot's: spoons are thin

    # ------------------------------------------------------------ building
    def _build(self) -> None:
        p, c, w = self.p, self.cid, self.world
        self._build_ground()
        self.drawers: dict = {}
        self.trays: dict[str, int] = {}
        self.radius: dict[str, float] = {}
        self.height: dict[str, float] = {}
        self.believed_in: dict[str, str] = {}   # object -> container it was seen to be in
        self.hold_tray = None
        self.arm_held: dict[str, Optional[str]] = {a: None for a in self.ARMS}
        for f in w.furniture.values():
            self._load_table(f.name, f.x, f.y, w.places[f.approach].theta + math.pi / 2)
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
            self.body_of[t.name] = self._make_cylinder(r, h, 0.1, rgba, x, y, z + h / 2 + 0.002)
        start = w.place(w.robot_at)
        with quiet_fds():
            self._load_base(start.x, start.y, start.theta)
        self.arm_body = {}
        self.q_cmd: dict[str, list] = {}
        self.f_cmd: dict[str, float] = {}
        self.arm_grip: dict[str, Optional[int]] = {}
        for arm in self.ARMS:
            body = p.loadURDF("franka_panda/panda.urdf", self._arm_mount(arm),
                              yaw_quat(p, start.theta), useFixedBase=True, physicsClientId=c)
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
        self._run(self._settle(0.5))

    # ------------------------------------------------------------ clock and base
    def _physics_step(self) -> None:
        p, c = self.p, self.cid
        if self.hold_tray is not None:
            self._follow_tray()
        for arm, body in self.arm_body.items():   # nothing pushes the arms around
            f = self.f_cmd[arm]
            p.resetJointStatesMultiDof(body, ARM_AND_FINGERS,
                                       [[v] for v in self.q_cmd[arm]] + [[f], [f]],
                                       physicsClientId=c)
        super()._physics_step()

    def _mounted(self) -> list:
        return [(body, self._arm_mount(arm)) for arm, body in self.arm_body.items()]

    def _speeds(self) -> tuple[float, float]:
        """Slower with the tray, so what stands on it does not slide."""
        return (TRAY_BASE_SPEED, TRAY_TURN_SPEED) if self.hold_tray else (BASE_SPEED, TURN_SPEED)

    def _accelerations(self) -> tuple[float, float]:
        """Gentler with the tray: what stands on it is held by friction only."""
        return (TRAY_ACCEL, TRAY_TURN_ACCEL) if self.hold_tray else super()._accelerations()

    def _carried_objects(self) -> list[str]:
        return [o for o in self.arm_held.values() if o]

    def _carried_bodies(self) -> set:
        out = {self.body_of[o] for o in self._carried_objects()}
        if self.hold_tray is not None:
            out.add(self.trays[self.hold_tray.tray])
            out |= {self.body_of[o] for o in self.hold_tray.riders}
        return out

    def _drop_while_carrying(self) -> None:
        held = [a for a in self.ARMS if self.arm_held[a]]
        if held:
            arm = self.rng.choice(held)
            with self._using(arm):
                self._slip(self.held, f"{arm} gripper while driving")

    # ------------------------------------------------------------ world queries
    def _touching(self, a: int, b: int) -> bool:
        return bool(self.p.getContactPoints(bodyA=a, bodyB=b, physicsClientId=self.cid))

    def _on_table(self, body: int, area: str) -> bool:
        table = self.body_of.get(area)
        if table is None or area not in self.furniture_top:
            return False
        top = self.furniture_top[area]
        return any(cp[5][2] >= top - 0.02 for cp in self.p.getContactPoints(
            bodyA=body, bodyB=table, physicsClientId=self.cid))

    def _area_of(self, where: str) -> str:
        if where in self.drawers:
            return self.drawers[where].area
        return where

    def _look_target(self, area: str) -> list[float]:
        x, y = self._to_world(area, 0.85, 0.0)
        return [x, y, self.furniture_top.get(area, 0.6)]

    # ------------------------------------------------------------ skills
    @skill("move_base")
    def move_base(self, place: str):
        """Back away from the table, drive to a pose in front of the goal's
        table, turn to face it and drive up to it: turning in place next to a
        table (or an open drawer) would sweep the arms through it."""
        goal = self.world.place(place)
        fraction = self._nav_fault(place)
        slip = self._carry_slip()
        x, y, yaw = self.base
        here = next((a for a, pl in self.world.places.items()
                     if math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE), None)
        if math.hypot(goal.x - x, goal.y - y) > POSE_TOLERANCE:
            if here in self.furniture_top:
                yield from self._drive(x - DOCK * math.cos(yaw), y - DOCK * math.sin(yaw))
            dock = DOCK if place in self.furniture_top else 0.0
            px, py = goal.x - dock * math.cos(goal.theta), goal.y - dock * math.sin(goal.theta)
            yield from self._face(px, py)
            yield from self._drive(px, py, fraction, slip)
            if fraction < 1.0:
                return SkillResult(True, self._stopped_at())
        yield from self._turn_to(goal.theta)
        if math.hypot(goal.x - self.base[0], goal.y - self.base[1]) > XY_TOL:
            yield from self._drive(goal.x, goal.y)
        yield from self._step(12)
        return SkillResult(True, self._stopped_at())

    @skill("detect_object")
    def detect_object(self, obj: str, where: str):
        """Look at the area's table. An object in a closed drawer cannot be
        seen: the robot sees the drawer it is in (which it knows)."""
        self.detections.pop(obj, None)
        self.believed_in.pop(obj, None)
        if obj not in self.body_of:
            return SkillResult(False, f"unknown object {obj}")
        area = self._area_of(where)
        target = self._look_target(area)
        pixels = self._look(obj, target)
        yield from self._step()
        if pixels >= 5:
            return SkillResult(True, f"{obj} seen ({pixels} px)", {"pixels": pixels})
        for d in self.drawers.values():
            if d.area == area and d.out < 0.02 and self._in_drawer(obj, d) and \
                    self._visible_pixels(f"{d.name}-housing", target) >= 5:
                self.believed_in[obj] = d.name
                return SkillResult(True, f"{obj} is in the closed {d.name}")
        return SkillResult(True, f"{obj} not seen")

    @skill("grasp")
    def grasp(self, obj: str, where: str, arm: Optional[str] = None):
        """Top grasp at the detected pose: open, descend, close, lift, hold at the side."""
        arm = self._pick_arm(arm)
        if arm is None:
            return SkillResult(False, "both hands are full")
        if self.arm_held[arm] is not None:
            return SkillResult(False, f"the {arm} hand already holds {self.arm_held[arm]}")
        if obj not in self.detections:        # e.g. in a drawer, or on a retry: look first
            yield from self.detect_object(obj, where)
        guess = self.detections.get(obj)
        if guess is None:
            return SkillResult(True, f"no detection of {obj} to grasp")
        if self.faults.moved and obj not in self._moved and self.rng.random() < self.faults.moved:
            self._moved.add(obj)   # somebody takes it away once, just before the grasp
            yield from self._move_object_elsewhere(obj, self._area_of(where))
        with self._using(arm):
            return (yield from self._top_grasp(obj, guess))

    def _move_object_elsewhere(self, obj: str, area: str):
        """Fault: somebody takes the object to a free spot on another table."""
        for other in sorted(a for a in self.furniture_top if a != area):
            spot = self._free_spot(other, None, self.radius[obj], skip=(obj,))
            if spot is not None:
                x, y, z = spot
                self.inject("moved", f"{obj} taken from {area} to {other}")
                self.p.resetBasePositionAndOrientation(
                    self.body_of[obj], [x, y, z + self.height[obj] / 2 + 0.002], [0, 0, 0, 1],
                    physicsClientId=self.cid)
                yield from self._settle(0.2)
                return

    def _top_grasp(self, obj: str, guess):
        gx, gy, gz = guess
        r = self.radius[obj]
        clear = gz + self.height[obj] / 2 + 0.12
        self._set_fingers(0.04)
        if not (yield from self._reach([gx, gy, clear], 0.8)) or \
                not (yield from self._reach([gx, gy, gz + 0.01], 0.6)):
            yield from self._rest_pose()
            return SkillResult(False, f"{obj} is out of the {self.active} arm's reach")
        yield from self._close_fingers(max(0.004, r - 0.005))
        self._close_on(obj)
        if self.held and self.faults.slip and self.rng.random() < self.faults.slip:
            yield from self._reach([gx, gy, gz + 0.03], 0.2)
            self._slip(obj, f"{self.active} gripper")
            yield from self._settle(0.3)
        lifted = yield from self._reach([gx, gy, clear], 0.5)
        self.detections.pop(obj, None)
        self.believed_in.pop(obj, None)
        yield from self._rest_pose()
        if not lifted:
            return SkillResult(False, "could not lift the arm")
        return SkillResult(True, f"{self.active} gripper closed")

    def _put_down(self, obj: str, x: float, y: float, z: float, what: str):
        """Lower what the selected hand holds onto (x, y) of a surface at z, let go."""
        if not (yield from self._put_down_at(x, y, z + self.height[obj] / 2, 0.12, 0.012)):
            return SkillResult(False, f"{what} is out of the {self.active} arm's reach")
        yield from self._rest_pose()
        return SkillResult(True, f"{self.active} gripper opened over {what}")

    @skill("place_object")
    def place_object(self, obj: str, where: str, arm: Optional[str] = None):
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
            return (yield from self._put_down(obj, *spot, what=f"the table of {where}"))

    # ------------------------------------------------------------ checks (monitors)
    GRIP_TOLERANCE = 0.06    # as tuned for the kitchen robot's grasps

    def _gripper_of(self, obj: str):
        arm = next((a for a in self.ARMS if self.arm_held[a] == obj), None)
        if arm is None:
            return None
        return self._ee_of(arm), self.arm_grip[arm], f"the {arm} gripper"

    @check("on")
    def check_on(self, obj: str, where: str) -> Check:
        if obj not in self.body_of:
            return Check(False, f"no object {obj}")
        body = self.body_of[obj]
        where_now = next((a for a in self.furniture_top if self._on_table(body, a)), None)
        ok = where_now == where and obj not in self.arm_held.values()
        return Check(ok, f"{obj} rests on {('the table of ' + where_now) if where_now else 'nothing'}")

    @check("detection")
    def check_detection(self, obj: str) -> Check:
        if obj in self.believed_in:
            d = self.drawers[self.believed_in[obj]]
            ok = self._in_drawer(obj, d)
            return Check(ok, f"{obj} {'is' if ok else 'is not'} in {d.name}")
        return super().check_detection(obj)

    # ------------------------------------------------------------ state estimation
    def observe(self) -> list[tuple[str, tuple]]:
        facts: list[tuple[str, tuple]] = []
        here = self._place_here()
        if here is None:   # stopped on the way: a new area where the robot stands
            x, y, _ = self.base
            facts += [("area", ("here", round(x, 3), round(y, 3))), ("robot-at", ("here",))]
        else:
            facts.append(("robot-at", (here,)))
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
            if self._is_open(d):
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


__all__ = ["KitchenRobot", "DRAWER_OPEN"]
