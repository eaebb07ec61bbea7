"""The kitchen in PyBullet: a Husky base with two Franka Panda arms, tables,
a drawer and a tray, for the pick-and-place domain (``domains/kitchen.jshop``).

The world comes from a kitchen problem's initial state
(:func:`htn.robot.world.kitchen_world_from_state`): each working area gets a table
in front of its base pose. Objects are cylinders sized by kind (bowl, cup,
spoon, ...). The robot holds the parts both PyBullet robots have
(:mod:`~htn.robot.simulated`: base, head camera, overview camera), two arms
(:mod:`~htn.robot.two_arms`), and the kitchen's own: the drawers
(:mod:`~htn.robot.drawer`), the trays (:mod:`~htn.robot.tray`) and the spots
on the tables (:mod:`~htn.robot.table_spots`).

Motion is kinematic and everything else is physics: objects rest on tables,
in the drawer and on the tray, and ride on the tray by friction while it is
carried. Geometry is in each area's frame (:mod:`~htn.robot.areas`): ``u``
forward from the base pose towards the table, ``v`` to the robot's left.
"""

from __future__ import annotations

import math

from htn.jshop.language.errors import HtnError

from .areas import AreaFrames
from .base import LIMITS, POSE_TOLERANCE, MobileBase
from .camera import OverviewCamera
from .drawer import DRAWER_OPEN, Drawer, Drawers, in_drawer_spot, make_drawer
from .drive import XY_TOL, Limits
from .interface import Check, SkillResult, check, skill
from .perception import Perception
from .simulated import SimulatedRobot
from .table_spots import TableSpots
from .tray import Trays, make_tray
from .two_arms import Hands, SideArm, TwoArms

SHAPES = {  # kind -> (radius, height, colour)
    "bowl": (0.035, 0.06, (0.95, 0.95, 0.9, 1)),
    "cup": (0.03, 0.09, (0.2, 0.4, 0.9, 1)),
    "spoon": (0.02, 0.08, (0.6, 0.6, 0.65, 1)),
}
DEFAULT_SHAPE = (0.033, 0.12, (0.9, 0.2, 0.1, 1))
TRAY_LIMITS = Limits(0.35, 0.6, 0.3, 0.6)  # m/s, rad/s, m/s^2, rad/s^2: with the tray
DOCK = 0.35  # backing away from a table before turning


class KitchenRobot(SimulatedRobot):
    """The simulated two-armed kitchen robot; ``gui=True`` opens a window."""

    GRIP_TOLERANCE = 0.06  # as tuned for the kitchen robot's grasps

    # ------------------------------------------------------------ building
    def _build(self) -> None:
        """The tables, drawers, trays and objects, then the parts. The
        objects are placed with the table spots before the base and the arms
        are loaded: the bodies are made in this order."""
        ph, w = self.physics, self.world
        p, c = ph.p, ph.cid
        ph.build_ground()
        self.frames = frames = AreaFrames(w)
        self.radius: dict[str, float] = {}
        self.height: dict[str, float] = {}
        self.believed_in: dict[str, str] = {}  # object -> container it was seen to be in
        hands: Hands = {a: None for a in TwoArms.NAMES}
        for f in w.furniture.values():
            ph.load_table(f.name, f.x, f.y, w.places[f.approach].theta + math.pi / 2)
        drawers = {
            name: make_drawer(ph, frames, name, area, opened=name in w.opened)
            for name, area in w.containers.items()
        }
        trays = {name: make_tray(ph, frames, name, area) for name, area in w.trays.items()}
        self.spots = TableSpots(ph, frames, w, drawers, trays, self.radius, hands)
        for t in w.things.values():
            r, h, rgba = SHAPES.get(t.kind, DEFAULT_SHAPE)
            self.radius[t.name], self.height[t.name] = r, h
            if t.on in w.containers:
                used = sum(1 for o in w.things.values() if o.on == t.on and o.name in ph.body_of)
                x, y, z = in_drawer_spot(ph, frames, drawers[t.on], used)
            else:
                spot = self.spots.free_spot(t.on, None, r)
                if spot is None:
                    raise HtnError(f"no room for {t.name} on the table of {t.on}")
                x, y, z = spot
            ph.body_of[t.name] = ph.make_cylinder(r, h, 0.1, rgba, x, y, z + h / 2 + 0.002)
        self.base = MobileBase(ph, w, self.draws, w.place(w.robot_at), self._limits)
        self.arms = TwoArms(ph, self.base, self.draws, hands)
        bodies = [self.base.body, *(arm.body for arm in self.arms.all())]
        for a in bodies:
            for b in bodies:
                if a < b:
                    for j in range(-1, p.getNumJoints(a, physicsClientId=c)):
                        for k in range(-1, p.getNumJoints(b, physicsClientId=c)):
                            p.setCollisionFilterPair(a, b, j, k, 0, physicsClientId=c)
        self.drawers = Drawers(ph, frames, w, self.arms, drawers)
        self.trays = Trays(ph, frames, w, self.base, self.arms, self.spots.footprints, trays)
        self.perception = Perception(ph, self.base, self.draws, (160, 120))  # spoons are thin
        self.camera = OverviewCamera(ph, self.base)
        ph.before_step += [self.trays.follow, self.arms.keep_joints]
        ph.body_of[w.robot] = self.base.body
        ph.run(ph.settle(0.5))

    # ------------------------------------------------------------ what the robot carries
    def _limits(self) -> Limits:
        """Slower and gentler with the tray: what stands on it is held by friction only."""
        return TRAY_LIMITS if self.trays.hold else LIMITS

    def _holding(self, obj: str) -> SideArm | None:
        return self.arms.holding(obj)

    def _carried_bodies(self) -> set:
        ph, hold = self.physics, self.trays.hold
        out = {ph.body_of[o] for o in self.arms.held_objects()}
        if hold is not None:
            out.add(self.trays.bodies[hold.tray])
            out |= {ph.body_of[o] for o in hold.riders}
        return out

    def _drop_while_carrying(self) -> None:
        held = [a for a in TwoArms.NAMES if self.arms.hands[a]]
        if held:
            arm = self.arms[self.draws.rng.choice(held)]
            assert arm.held is not None  # its hand holds something
            arm.slip(arm.held, f"{arm.name} gripper while driving")

    def _hand_with(self, obj: str, arm: str | None) -> str | None:
        """``arm`` if it names one, else the arm that holds ``obj``."""
        if arm in TwoArms.NAMES:
            return arm
        return next((a for a in TwoArms.NAMES if self.arms.hands[a] == obj), None)

    # ------------------------------------------------------------ world queries
    def _area_of(self, where: str) -> str:
        if where in self.drawers:
            return self.drawers[where].area
        return where

    def _look_target(self, area: str) -> list[float]:
        x, y = self.frames.to_world(area, 0.85, 0.0)
        return [x, y, self.physics.furniture_top.get(area, 0.6)]

    # ------------------------------------------------------------ skills
    @skill("move_base")
    def move_base(self, place: str):
        """Back away from the table, drive to a pose in front of the goal's
        table, turn to face it and drive up to it: turning in place next to a
        table (or an open drawer) would sweep the arms through it."""
        base, tops = self.base, self.physics.furniture_top
        goal = self.world.place(place)
        fraction = base.nav_fault(place)
        slip = base.carry_slip(bool(self.arms.held_objects()))
        x, y, yaw = base.pose
        here = next(
            (
                a
                for a, pl in self.world.places.items()
                if math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE
            ),
            None,
        )
        if math.hypot(goal.x - x, goal.y - y) > POSE_TOLERANCE:
            if here in tops:
                yield from base.drive(x - DOCK * math.cos(yaw), y - DOCK * math.sin(yaw))
            dock = DOCK if place in tops else 0.0
            px, py = goal.x - dock * math.cos(goal.theta), goal.y - dock * math.sin(goal.theta)
            yield from base.face(px, py)
            yield from base.drive(px, py, fraction, slip, self._drop_while_carrying)
            if fraction < 1.0:
                return SkillResult(True, base.stopped_at())
        yield from base.turn_to(goal.theta)
        if math.hypot(goal.x - base.pose[0], goal.y - base.pose[1]) > XY_TOL:
            yield from base.drive(goal.x, goal.y)
        yield from self.physics.step(12)
        return SkillResult(True, base.stopped_at())

    @skill("detect_object")
    def detect_object(self, obj: str, where: str):
        """Look at the area's table. An object in a closed drawer cannot be
        seen: the robot sees the drawer it is in (which it knows)."""
        self.perception.detections.pop(obj, None)
        self.believed_in.pop(obj, None)
        if obj not in self.physics.body_of:
            return SkillResult(False, f"unknown object {obj}")
        area = self._area_of(where)
        target = self._look_target(area)
        pixels = self.perception.look(obj, target)
        yield from self.physics.step()
        if pixels >= 5:
            return SkillResult(True, f"{obj} seen ({pixels} px)", {"pixels": pixels})
        for d in self.drawers.values():
            if (
                d.area == area
                and d.out < 0.02
                and self.drawers.holds(obj, d)
                and self.perception.visible_pixels(f"{d.name}-housing", target) >= 5
            ):
                self.believed_in[obj] = d.name
                return SkillResult(True, f"{obj} is in the closed {d.name}")
        return SkillResult(True, f"{obj} not seen")

    @skill("grasp")
    def grasp(self, obj: str, where: str, arm: str | None = None):
        """Top grasp at the detected pose: open, descend, close, lift, hold at the side."""
        arm = self.arms.pick(arm)
        if arm is None:
            return SkillResult(False, "both hands are full")
        if self.arms.hands[arm] is not None:
            return SkillResult(False, f"the {arm} hand already holds {self.arms.hands[arm]}")
        guess = yield from self._grasp_target(obj, where, self._area_of(where))
        if guess is None:
            return SkillResult(True, f"no detection of {obj} to grasp")
        return (yield from self._top_grasp(self.arms[arm], obj, guess))

    def _move_object_elsewhere(self, obj: str, area: str):
        """Fault: somebody takes the object to a free spot on another table."""
        ph = self.physics
        for other in sorted(a for a in ph.furniture_top if a != area):
            spot = self.spots.free_spot(other, None, self.radius[obj], skip=(obj,))
            if spot is not None:
                x, y, z = spot
                self.draws.inject("moved", f"{obj} taken from {area} to {other}")
                ph.p.resetBasePositionAndOrientation(
                    ph.body_of[obj],
                    [x, y, z + self.height[obj] / 2 + 0.002],
                    [0, 0, 0, 1],
                    physicsClientId=ph.cid,
                )
                yield from ph.settle(0.2)
                return

    def _top_grasp(self, arm: SideArm, obj: str, guess):
        gx, gy, gz = guess
        r = self.radius[obj]
        clear = gz + self.height[obj] / 2 + 0.12
        arm.set_fingers(0.04)
        if not (yield from arm.reach([gx, gy, clear], 0.8)) or not (
            yield from arm.reach([gx, gy, gz + 0.01], 0.6)
        ):
            yield from arm.rest()
            return SkillResult(False, f"{obj} is out of the {arm.name} arm's reach")
        yield from arm.close_fingers(max(0.004, r - 0.005))
        arm.close_on(obj)
        if arm.held and self.draws.happens("slip"):
            yield from arm.reach([gx, gy, gz + 0.03], 0.2)
            arm.slip(obj, f"{arm.name} gripper")
            yield from self.physics.settle(0.3)
        lifted = yield from arm.reach([gx, gy, clear], 0.5)
        self.perception.detections.pop(obj, None)
        self.believed_in.pop(obj, None)
        yield from arm.rest()
        if not lifted:
            return SkillResult(False, "could not lift the arm")
        return SkillResult(True, f"{arm.name} gripper closed")

    def _put_down(self, arm: SideArm, obj: str, x: float, y: float, z: float, what: str):
        """Lower what ``arm`` holds onto (x, y) of a surface at z, let go."""
        if not (yield from arm.put_down_at(x, y, z + self.height[obj] / 2, 0.12, 0.012)):
            return SkillResult(False, f"{what} is out of the {arm.name} arm's reach")
        yield from arm.rest()
        return SkillResult(True, f"{arm.name} gripper opened over {what}")

    @skill("place_object")
    def place_object(self, obj: str, where: str, arm: str | None = None):
        arm = self._hand_with(obj, arm)
        if arm is None or self.arms.hands[arm] != obj:
            return SkillResult(True, f"{obj} is not in the {arm or 'robot'}'s hand")
        if where not in self.physics.furniture_top:
            return SkillResult(False, f"no table at {where}")
        spot = self.spots.free_spot(where, self.arms[arm], self.radius[obj])
        if spot is None:
            return SkillResult(False, f"no free spot within reach on the table of {where}")
        return (yield from self._put_down(self.arms[arm], obj, *spot, what=f"the table of {where}"))

    @skill("open_container")
    def open_container(self, container: str):
        return self.drawers.pull(container, opened=True)

    @skill("close_container")
    def close_container(self, container: str):
        return self.drawers.pull(container, opened=False)

    @skill("put_on_tray")
    def put_on_tray(self, obj: str, tray: str, arm: str | None = None):
        arm = self._hand_with(obj, arm)
        if tray not in self.trays.bodies:
            return SkillResult(False, f"no tray {tray}")
        if arm is None or self.arms.hands[arm] != obj:
            return SkillResult(True, f"{obj} is not in the {arm or 'robot'}'s hand")
        spot = self.trays.free_spot(tray, arm)
        if spot is None:
            return SkillResult(False, f"no free spot on {tray} within the {arm} arm's reach")
        return (yield from self._put_down(self.arms[arm], obj, *spot, what=f"{tray}"))

    @skill("take_from_tray")
    def take_from_tray(self, obj: str, tray: str, arm: str | None = None):
        arm = self.arms.pick(arm)
        if arm is None or self.arms.hands[arm] is not None:
            return SkillResult(False, f"the {arm or 'robot'}'s hand is not free")
        if tray not in self.trays.bodies or obj not in self.physics.body_of:
            return SkillResult(False, f"unknown tray or object {tray}/{obj}")
        if self.perception.visible_pixels(obj, list(self.physics.body_pos(tray))) < 5:
            return SkillResult(True, f"{obj} is not seen on {tray}")
        return (yield from self._top_grasp(self.arms[arm], obj, self.perception.noisy_pos(obj)))

    @skill("lift_tray")
    def lift_tray(self, tray: str):
        return self.trays.lift(tray)

    @skill("lower_tray")
    def lower_tray(self, tray: str, where: str):
        return self.trays.lower(tray, where)

    # ------------------------------------------------------------ checks (monitors)
    @check("on")
    def check_on(self, obj: str, where: str) -> Check:
        ph = self.physics
        if obj not in ph.body_of:
            return Check(False, f"no object {obj}")
        body = ph.body_of[obj]
        where_now = next((a for a in ph.furniture_top if ph.on_top(body, a)), None)
        ok = where_now == where and obj not in self.arms.hands.values()
        return Check(
            ok, f"{obj} rests on {('the table of ' + where_now) if where_now else 'nothing'}"
        )

    @check("detection")
    def check_detection(self, obj: str) -> Check:
        if obj in self.believed_in:
            d = self.drawers[self.believed_in[obj]]
            ok = self.drawers.holds(obj, d)
            return Check(ok, f"{obj} {'is' if ok else 'is not'} in {d.name}")
        return super().check_detection(obj)

    @check("opened")
    def check_opened(self, container: str, opened: bool) -> Check:
        return self.drawers.check_opened(container, opened)

    @check("on_tray")
    def check_on_tray(self, obj: str, tray: str) -> Check:
        return self.trays.check_on_tray(obj, tray)

    @check("tray_carried")
    def check_tray_carried(self, tray: str, carried: bool, where: str | None = None) -> Check:
        return self.trays.check_carried(tray, carried, where)

    # ------------------------------------------------------------ state estimation
    def observe(self) -> list[tuple[str, tuple]]:
        ph, hold = self.physics, self.trays.hold
        facts: list[tuple[str, tuple]] = []
        here = self.base.place_here()
        if here is None:  # stopped on the way: a new area where the robot stands
            x, y, _ = self.base.pose
            facts += [("area", ("here", round(x, 3), round(y, 3))), ("robot-at", ("here",))]
        else:
            facts.append(("robot-at", (here,)))
        for arm in TwoArms.NAMES:
            obj = self.arms.hands[arm]
            if obj is not None and self.check_in_gripper(obj).ok:
                facts.append(("holding", (arm, obj)))
            elif hold is None:
                facts.append(("free", (arm,)))
        for t in self.world.things:
            body = ph.body_of[t]
            area = next((a for a in ph.furniture_top if ph.on_top(body, a)), None)
            d = self.drawers.container_of(t)
            if area is not None:
                facts.append(("at", (t, area)))
            elif d is not None:
                facts.append(("in", (t, d.name)))
        for name, d in self.drawers.items():
            if self.drawers.is_open(d):
                facts.append(("opened", (name,)))
        for tray, bid in self.trays.bodies.items():
            if hold is not None and hold.tray == tray:
                facts.append(("carrying-tray", (tray,)))
            else:
                area = next((a for a in ph.furniture_top if ph.on_top(bid, a)), None)
                if area is not None:
                    facts.append(("tray", (tray, area)))
            facts += [("on-tray", (t, tray)) for t in self.trays.on_tray(tray)]
        return facts

    # ------------------------------------------------------------ read by the tests' oracle
    @property
    def arm_body(self) -> dict[str, int]:
        return {arm.name: arm.body for arm in self.arms.all()}

    def _in_drawer(self, obj: str, d: Drawer) -> bool:
        return self.drawers.holds(obj, d)

    def _is_open(self, d: Drawer) -> bool:
        return self.drawers.is_open(d)


__all__ = ["KitchenRobot", "DRAWER_OPEN"]
