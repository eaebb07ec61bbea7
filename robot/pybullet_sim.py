"""A simulated domestic robot in PyBullet: a Husky base carrying a Franka Panda.

The world is built from the problem's initial state (:mod:`htn.robot.world`):
tables from ``table/table.urdf``, objects as small cylinders, persons as
upright capsules with a hand point, the robot at its start location. The robot
holds its parts (:mod:`~htn.robot.simulated`): the base, one arm
(:mod:`~htn.robot.arm`), the head camera and the overview camera.

Motion is deterministic (the base under its motion controller,
:mod:`~htn.robot.drive`; the arm placed joint by joint); everything else is physics: objects
fall, rest on surfaces and collide. Every skill is a generator advancing the
simulation one physics step at a time (see :mod:`htn.robot.interface`). A
person takes an object the same way a gripper holds one, when the gripper
brings it within reach.

Faults (``slip``, ``nav``, ``detect``, ``moved``) are injected with a seeded
random generator, so the same seed gives the same run.
"""

from __future__ import annotations

import math

from .arm import ARM_JOINTS, Arm
from .base import MobileBase
from .camera import OverviewCamera
from .drive import XY_TOL
from .faults import Faults
from .interface import Check, SkillResult, check, skill
from .perception import Perception
from .simulated import SimulatedRobot
from .world import World

MOUNT = (0.2, 0.0, 0.48)  # panda base relative to the husky base
ARM_HOME = (1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785)  # tucked to the left, out of the camera's view
CAN_RADIUS, CAN_HEIGHT = 0.033, 0.12
PERSON_RADIUS, PERSON_HEIGHT = 0.2, 1.6
HAND_REACH = 0.7  # a person takes an object within this distance of their axis


class PyBulletRobot(SimulatedRobot):
    """The simulated domestic robot; ``gui=True`` opens a window (needs a display)."""

    def __init__(
        self,
        world: World,
        gui: bool = False,
        faults: Faults | None = None,
        seed: int = 0,
        speech=None,
    ):
        self.seen_persons: dict[str, tuple] = {}
        self._person_constraints: dict[str, tuple] = {}  # object -> (person, constraint)
        super().__init__(world, gui, faults, seed, speech)

    # ------------------------------------------------------------ building
    def _build(self) -> None:
        """The world's bodies, then the robot's parts: the base, the arm on it,
        the head camera and the overview camera."""
        ph, w = self.physics, self.world
        p, c = ph.p, ph.cid
        ph.build_ground()
        for f in w.furniture.values():
            if f.kind == "tray":
                bid = p.loadURDF(
                    "tray/traybox.urdf", [f.x, f.y, 0.0], useFixedBase=True, physicsClientId=c
                )
                ph.body_of[f.name] = bid
                ph.furniture_top[f.name] = p.getAABB(bid, physicsClientId=c)[1][2]
            else:
                ph.load_table(f.name, f.x, f.y)
        slots: dict[str, int] = {}
        for t in w.things.values():
            if t.on is None:
                continue
            x, y, z = self._spot_on(t.on, slots.get(t.on, 0))
            slots[t.on] = slots.get(t.on, 0) + 1
            ph.body_of[t.name] = ph.make_cylinder(
                CAN_RADIUS, CAN_HEIGHT, 0.15, [0.9, 0.2, 0.1, 1], x, y, z + CAN_HEIGHT / 2 + 0.002
            )
        for person in w.persons.values():
            col = p.createCollisionShape(
                p.GEOM_CAPSULE,
                radius=PERSON_RADIUS,
                height=PERSON_HEIGHT - 2 * PERSON_RADIUS,
                physicsClientId=c,
            )
            vis = p.createVisualShape(
                p.GEOM_CAPSULE,
                radius=PERSON_RADIUS,
                length=PERSON_HEIGHT - 2 * PERSON_RADIUS,
                rgbaColor=[0.2, 0.4, 0.9, 1],
                physicsClientId=c,
            )
            ph.body_of[person.name] = p.createMultiBody(
                0, col, vis, [person.x, person.y, PERSON_HEIGHT / 2], physicsClientId=c
            )
        self.base = MobileBase(ph, w, self.draws, w.place(w.robot_at))
        self.arm = Arm(ph, self.base, self.draws, MOUNT)
        for j in range(-1, p.getNumJoints(self.base.body, physicsClientId=c)):
            for k in range(-1, p.getNumJoints(self.arm.body, physicsClientId=c)):
                p.setCollisionFilterPair(self.base.body, self.arm.body, j, k, 0, physicsClientId=c)
        self.arm.set_q(ARM_HOME)
        self.arm.set_fingers(0.04)
        self.perception = Perception(ph, self.base, self.draws, (96, 72))
        self.camera = OverviewCamera(ph, self.base)
        ph.body_of[w.robot] = self.base.body
        ph.run(ph.settle(0.5))

    def _spot_on(self, furniture: str, slot: int) -> tuple[float, float, float]:
        """Where the ``slot``-th object stands: near the edge facing the robot."""
        f = self.world.furniture[furniture]
        ap = self.world.place(f.approach)
        ph = self.physics
        (x0, y0, _), (x1, y1, z1) = ph.p.getAABB(ph.body_of[furniture], physicsClientId=ph.cid)
        dx, dy = ap.x - f.x, ap.y - f.y
        offset = 0.16 * ((slot + 1) // 2) * (1 if slot % 2 else -1)
        if abs(dx) >= abs(dy):
            return ((x0 + 0.14) if dx < 0 else (x1 - 0.14)), f.y + offset, z1
        return f.x + offset, ((y0 + 0.14) if dy < 0 else (y1 - 0.14)), z1

    # ------------------------------------------------------------ what the robot carries
    def _holding(self, obj: str) -> Arm | None:
        return self.arm if self.arm.held == obj else None

    def _carried_objects(self) -> list[str]:
        return [self.arm.held] if self.arm.held else []

    def _carried_bodies(self) -> set:
        return {self.physics.body_of[self.arm.held]} if self.arm.held else set()

    def _drop_while_carrying(self) -> None:
        if self.arm.held:
            self.arm.slip(self.arm.held, "gripper while driving")

    # ------------------------------------------------------------ skills
    @skill("move_base")
    def move_base(self, place: str):
        goal = self.world.place(place)
        fraction = self.base.nav_fault(place)
        slip = self.base.carry_slip(bool(self._carried_objects()))
        if math.hypot(goal.x - self.base.pose[0], goal.y - self.base.pose[1]) > XY_TOL:
            yield from self.base.face(goal.x, goal.y)
            yield from self.base.drive(goal.x, goal.y, fraction, slip, self._drop_while_carrying)
        if fraction == 1.0:
            yield from self.base.turn_to(goal.theta)
        yield from self.physics.step(12)
        return SkillResult(True, self.base.stopped_at())

    @skill("detect_object")
    def detect_object(self, obj: str, furniture: str):
        ph = self.physics
        self.perception.detections.pop(obj, None)
        if obj not in ph.body_of or furniture not in ph.body_of:
            return SkillResult(False, f"unknown object or furniture {obj}/{furniture}")
        target = ph.body_pos(furniture)
        target[2] = ph.furniture_top[furniture]
        yield from self.base.face(target[0], target[1])
        pixels = self.perception.look(obj, target)
        detail = f"{obj} seen ({pixels} px)" if pixels >= 5 else f"{obj} not seen"
        return SkillResult(True, detail, {"pixels": pixels})

    def _move_object_elsewhere(self, obj: str, furniture: str):
        """Fault: somebody takes the object to another piece of furniture."""
        ph = self.physics
        others = [f for f in self.world.furniture if f != furniture and f in ph.furniture_top]
        if not others:
            return
        dest = self.draws.rng.choice(sorted(others))
        self.draws.inject("moved", f"{obj} taken from {furniture} to {dest}")
        used = sum(1 for t, _ in self._resting_objects() if t == dest)
        x, y, z = self._spot_on(dest, used + 1)
        ph.p.resetBasePositionAndOrientation(
            ph.body_of[obj],
            [x, y, z + CAN_HEIGHT / 2 + 0.002],
            [0, 0, 0, 1],
            physicsClientId=ph.cid,
        )
        yield from ph.settle(0.2)

    @skill("grasp")
    def grasp(self, obj: str, furniture: str):
        """Top grasp at the detected pose: open, descend, close, lift, carry.
        Without a detection (e.g. on a retry) it looks again first."""
        arm = self.arm
        if arm.held is not None:
            return SkillResult(False, f"the hand already holds {arm.held}")
        guess = yield from self._grasp_target(obj, furniture, furniture)
        if guess is None:
            return SkillResult(True, f"no detection of {obj} to grasp")
        gx, gy, gz = guess
        yield from self.base.face(gx, gy)
        yaw = self._grasp_yaw(obj)
        arm.set_fingers(0.04)
        if not (yield from arm.reach([gx, gy, gz + 0.15], 0.8, yaw=yaw)):
            return SkillResult(False, f"{obj} is out of the arm's reach")
        if not (yield from arm.reach([gx, gy, gz + 0.01], 0.6, yaw=yaw)):
            return SkillResult(False, f"{obj} is out of the arm's reach")
        yield from arm.close_fingers(0.028)
        arm.close_on(obj)
        if arm.held and self.draws.happens("slip"):
            # it slips just after it leaves the surface, while being lifted
            yield from arm.reach([gx, gy, gz + 0.03], 0.2, yaw=yaw)
            arm.slip(obj, "gripper")
            yield from self.physics.settle(0.3)
        lift_ok = yield from arm.reach([gx, gy, gz + 0.15], 0.5, yaw=yaw)
        yield from self._carry_pose()
        self.perception.detections.pop(obj, None)
        if not lift_ok:
            return SkillResult(False, "could not lift the arm")
        return SkillResult(True, "gripper closed")

    def _grasp_yaw(self, obj: str) -> float:
        """Close the fingers across the object: along the robot's side for an
        upright can, across the axis of a can lying on its side."""
        p, c = self.physics.p, self.physics.cid
        _, orn = p.getBasePositionAndOrientation(self.physics.body_of[obj], physicsClientId=c)
        axis = p.getMatrixFromQuaternion(orn)[2::3]  # the cylinder's z axis in the world
        if abs(axis[2]) > 0.7:
            return self.base.pose[2]
        return math.atan2(axis[1], axis[0])

    def _carry_pose(self):
        """Hold the arm (and what it carries) close, to the left of the camera."""
        x, y, yaw = self.base.pose
        mx, my, _ = self.base.mount_pos(MOUNT)
        lx, ly = -math.sin(yaw), math.cos(yaw)
        fx, fy = math.cos(yaw), math.sin(yaw)
        if not (
            yield from self.arm.reach(
                [mx + 0.15 * fx + 0.3 * lx, my + 0.15 * fy + 0.3 * ly, 0.9], 0.7
            )
        ):
            yield from self.arm.move(ARM_HOME, 0.7)
        yield from self.physics.step(24)

    @skill("place_object")
    def place_object(self, obj: str, furniture: str):
        if self.arm.held != obj:
            return SkillResult(True, f"{obj} is not in the hand")
        used = sum(1 for t, _ in self._resting_objects() if t == furniture)
        x, y, z = self._spot_on(furniture, used)
        yield from self.base.face(x, y)
        if not (yield from self.arm.put_down_at(x, y, z + CAN_HEIGHT / 2, 0.15, 0.015)):
            return SkillResult(False, f"{furniture} is out of the arm's reach")
        yield from self._carry_pose()
        return SkillResult(True, f"released over {furniture}")

    @skill("find_person")
    def find_person(self, person: str):
        if person not in self.world.persons:
            return SkillResult(False, f"unknown person {person}")
        self.seen_persons.pop(person, None)
        x, y, yaw = self.base.pose
        best = 0
        for dyaw in (0.0, 0.7, -0.7):
            look = yaw + dyaw
            target = [x + 2.0 * math.cos(look), y + 2.0 * math.sin(look), 1.0]
            yield from self.base.turn_to(look)
            best = self.perception.visible_pixels(person, target)
            if best >= 20:
                pos = self.physics.body_pos(person)
                self.seen_persons[person] = (float(pos[0]), float(pos[1]))
                break
        yield from self.base.turn_to(yaw)
        return SkillResult(True, f"{person} {'seen' if best >= 20 else 'not seen'} ({best} px)")

    @skill("hand_over")
    def hand_over(self, obj: str, person: str):
        if self.arm.held != obj:
            return SkillResult(True, f"{obj} is not in the hand")
        where = self.seen_persons.get(person)
        if where is None:
            return SkillResult(True, f"{person} has not been found")
        px, py = where
        yield from self.base.face(px, py)
        mx, my, _ = self.base.mount_pos(MOUNT)
        d = math.hypot(px - mx, py - my)
        reach = min(0.62, max(0.3, d - 0.3))
        ux, uy = (px - mx) / d, (py - my) / d
        if not (yield from self.arm.reach([mx + reach * ux, my + reach * uy, 0.95], 1.0)):
            return SkillResult(False, "cannot extend the arm towards the person")
        ee = self.arm.ee()
        taker = self.world.persons[person]
        if taker.can_receive and math.hypot(ee[0] - px, ee[1] - py) <= HAND_REACH:
            body = self.physics.body_of[obj]
            self.arm.release()
            self.arm.set_fingers(0.04)
            self._give_to(person, body)
        yield from self.physics.step(24)
        yield from self._carry_pose()
        return SkillResult(True, "gripper opened")

    def _give_to(self, person: str, body: int) -> None:
        ph = self.physics
        p, c = ph.p, ph.cid
        pb = ph.body_of[person]
        ppos, porn = p.getBasePositionAndOrientation(pb, physicsClientId=c)
        bpos, born = p.getBasePositionAndOrientation(body, physicsClientId=c)
        inv = p.invertTransform(ppos, porn)
        rel = p.multiplyTransforms(inv[0], inv[1], bpos, born)
        cid = p.createConstraint(
            pb, -1, body, -1, p.JOINT_FIXED, [0, 0, 0], rel[0], [0, 0, 0], rel[1], physicsClientId=c
        )
        self._person_constraints[ph.bodies_named[body]] = (person, cid)

    # ------------------------------------------------------------ checks (monitors)
    def _resting_objects(self) -> list[tuple[str, str]]:
        """(furniture, object) pairs of objects resting on a furniture top."""
        out = []
        ph = self.physics
        for t in self.world.things:
            if t not in ph.body_of or t == self.arm.held:
                continue
            for f in ph.furniture_top:
                if ph.on_top(ph.body_of[t], f):
                    out.append((f, t))
                    break
        return out

    @check("on")
    def check_on(self, obj: str, furniture: str) -> Check:
        where = [f for f, t in self._resting_objects() if t == obj]
        ok = furniture in where and self.arm.held != obj
        return Check(ok, f"{obj} rests on {where[0] if where else 'nothing'}")

    @check("handed")
    def check_handed(self, obj: str, person: str) -> Check:
        ph = self.physics
        if obj not in ph.body_of or person not in ph.body_of:
            return Check(False, "unknown object or person")
        o, q = ph.body_pos(obj), ph.body_pos(person)
        d = math.hypot(o[0] - q[0], o[1] - q[1])
        holder = self._person_constraints.get(obj, (None,))[0]
        ok = holder == person and d <= HAND_REACH + 0.05 and o[2] > 0.5 and self.arm.held != obj
        return Check(ok, f"{obj} is {d:.2f} m from {person}, {o[2]:.2f} m high")

    @check("person_visible")
    def check_person_visible(self, person: str) -> Check:
        ph = self.physics
        if person not in ph.body_of:
            return Check(False, f"no person {person}")
        pos = ph.body_pos(person)
        d = math.hypot(pos[0] - self.base.pose[0], pos[1] - self.base.pose[1])
        px = self.perception.visible_pixels(person, [pos[0], pos[1], 1.0])
        ok = person in self.seen_persons and px >= 20 and d <= 3.0
        return Check(ok, f"{person}: {px} px at {d:.2f} m")

    # ------------------------------------------------------------ state estimation
    def observe(self) -> list[tuple[str, tuple]]:
        w = self.world
        facts: list[tuple[str, tuple]] = []
        at = self.base.place_here()
        if at is None:
            x, y, yaw = self.base.pose
            at = "here"
            facts.append(
                ("location", ("here", round(x, 3), round(y, 3), round(math.degrees(yaw), 2)))
            )
        facts.append(("robot_at", (w.robot, at)))
        held = self.arm.held
        if held is not None and self.check_in_gripper(held).ok:
            facts.append(("holding", (w.robot, held)))
        else:
            facts.append(("free_hand", (w.robot,)))
        for f, t in self._resting_objects():
            facts.append(("object_on", (t, f)))
        for obj, (person, _) in self._person_constraints.items():
            facts.append(("has", (person, obj)))
        return [
            (p, tuple(float(a) if isinstance(a, (int, float)) else a for a in args))
            for p, args in facts
        ]

    @property
    def arm_body(self) -> dict[str, int]:
        return {self.arm.name: self.arm.body}


__all__ = ["PyBulletRobot", "Faults", "ARM_JOINTS"]
