"""A simulated domestic robot in PyBullet: a Husky base carrying a Franka Panda.

The world is built from the problem's initial state (:mod:`htn.robot.world`):
tables from ``table/table.urdf``, objects as small cylinders, persons as
upright capsules with a hand point, the robot at its start location. The robot
is made of the parts in :mod:`~htn.robot.base`, :mod:`~htn.robot.arm` and
:mod:`~htn.robot.perception`, which the kitchen robot shares.

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
import random
from typing import Optional

from .arm import ARM_JOINTS, Arm
from .base import MobileBase
from .camera import OverviewCamera
from .drive import XY_TOL
from .faults import Faults
from .interface import Check, Robot, SkillResult, check, skill
from .odometry import Odometry
from .perception import Perception
from .physics import Physics, quiet_fds, yaw_quat
from .world import World

MOUNT = (0.2, 0.0, 0.48)  # panda base relative to the husky base
ARM_HOME = (1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785)   # tucked to the left, out of the camera's view
CAN_RADIUS, CAN_HEIGHT = 0.033, 0.12
PERSON_RADIUS, PERSON_HEIGHT = 0.2, 1.6
HAND_REACH = 0.7          # a person takes an object within this distance of their axis


class PyBulletRobot(Physics, MobileBase, Arm, Perception, OverviewCamera, Robot):
    """The simulated domestic robot; ``gui=True`` opens a window (needs a display)."""

    def __init__(self, world: World, gui: bool = False, faults: Optional[Faults] = None,
                 seed: int = 0, speech=None):
        self.world = world
        self.faults = faults or Faults()
        self.rng = random.Random(seed)
        self.spoken: list[str] = []
        self.injected: list[dict] = []       # faults injected so far (for tests and logs)
        self._moved: set = set()
        self.speech = speech
        self.detections: dict[str, tuple] = {}
        self.seen_persons: dict[str, tuple] = {}
        self._person_constraints: dict[str, tuple] = {}
        self._connect(gui)
        with quiet_fds():
            self._build()
        self.bodies_named = {v: k for k, v in self.body_of.items()}
        self.odometry = Odometry()      # distances from here on (htn evaluate --robot pybullet)
        self.odometry.sample(self)

    # ------------------------------------------------------------ building
    def _build(self) -> None:
        p, c, w = self.p, self.cid, self.world
        self._build_ground()
        for f in w.furniture.values():
            if f.kind == "tray":
                bid = p.loadURDF("tray/traybox.urdf", [f.x, f.y, 0.0], useFixedBase=True,
                                 physicsClientId=c)
                self.body_of[f.name] = bid
                self.furniture_top[f.name] = p.getAABB(bid, physicsClientId=c)[1][2]
            else:
                self._load_table(f.name, f.x, f.y)
        slots: dict[str, int] = {}
        for t in w.things.values():
            if t.on is None:
                continue
            x, y, z = self._spot_on(t.on, slots.get(t.on, 0))
            slots[t.on] = slots.get(t.on, 0) + 1
            self.body_of[t.name] = self._make_cylinder(CAN_RADIUS, CAN_HEIGHT, 0.15,
                                                       [0.9, 0.2, 0.1, 1], x, y,
                                                       z + CAN_HEIGHT / 2 + 0.002)
        for person in w.persons.values():
            col = p.createCollisionShape(p.GEOM_CAPSULE, radius=PERSON_RADIUS,
                                         height=PERSON_HEIGHT - 2 * PERSON_RADIUS, physicsClientId=c)
            vis = p.createVisualShape(p.GEOM_CAPSULE, radius=PERSON_RADIUS,
                                      length=PERSON_HEIGHT - 2 * PERSON_RADIUS,
                                      rgbaColor=[0.2, 0.4, 0.9, 1], physicsClientId=c)
            self.body_of[person.name] = p.createMultiBody(0, col, vis,
                                                          [person.x, person.y, PERSON_HEIGHT / 2],
                                                          physicsClientId=c)
        start = w.place(w.robot_at)
        self._load_base(start.x, start.y, start.theta)
        self.arm = p.loadURDF("franka_panda/panda.urdf", self._mount_pos(), yaw_quat(p, start.theta),
                              useFixedBase=True, physicsClientId=c)
        for j in range(-1, p.getNumJoints(self.husky, physicsClientId=c)):
            for k in range(-1, p.getNumJoints(self.arm, physicsClientId=c)):
                p.setCollisionFilterPair(self.husky, self.arm, j, k, 0, physicsClientId=c)
        self._set_arm_q(ARM_HOME)
        self._set_fingers(0.04)
        self.body_of[w.robot] = self.husky
        self._run(self._settle(0.5))

    def _spot_on(self, furniture: str, slot: int) -> tuple[float, float, float]:
        """Where the ``slot``-th object stands: near the edge facing the robot."""
        f = self.world.furniture[furniture]
        ap = self.world.place(f.approach)
        (x0, y0, _), (x1, y1, z1) = self.p.getAABB(self.body_of[furniture], physicsClientId=self.cid)
        dx, dy = ap.x - f.x, ap.y - f.y
        offset = 0.16 * ((slot + 1) // 2) * (1 if slot % 2 else -1)
        if abs(dx) >= abs(dy):
            return ((x0 + 0.14) if dx < 0 else (x1 - 0.14)), f.y + offset, z1
        return f.x + offset, ((y0 + 0.14) if dy < 0 else (y1 - 0.14)), z1

    # ------------------------------------------------------------ the parts' hooks
    def _mount_pos(self, base=None):
        x, y, yaw = base or self.base
        return [x + MOUNT[0] * math.cos(yaw) - MOUNT[1] * math.sin(yaw),
                y + MOUNT[0] * math.sin(yaw) + MOUNT[1] * math.cos(yaw), MOUNT[2]]

    def _mounted(self) -> list:
        return [(self.arm, self._mount_pos())]

    def _carried_objects(self) -> list[str]:
        return [self.held] if self.held else []

    def _carried_bodies(self) -> set:
        return {self.body_of[self.held]} if self.held else set()

    def _drop_while_carrying(self) -> None:
        if self.held:
            self._slip(self.held, "gripper while driving")

    # ------------------------------------------------------------ skills
    @skill("move_base")
    def move_base(self, place: str):
        goal = self.world.place(place)
        fraction = self._nav_fault(place)
        slip = self._carry_slip()
        if math.hypot(goal.x - self.base[0], goal.y - self.base[1]) > XY_TOL:
            yield from self._face(goal.x, goal.y)
            yield from self._drive(goal.x, goal.y, fraction, slip)
        if fraction == 1.0:
            yield from self._turn_to(goal.theta)
        yield from self._step(12)
        return SkillResult(True, self._stopped_at())

    @skill("detect_object")
    def detect_object(self, obj: str, furniture: str):
        self.detections.pop(obj, None)
        if obj not in self.body_of or furniture not in self.body_of:
            return SkillResult(False, f"unknown object or furniture {obj}/{furniture}")
        target = self._body_pos(furniture)
        target[2] = self.furniture_top[furniture]
        yield from self._face(target[0], target[1])
        pixels = self._look(obj, target)
        detail = f"{obj} seen ({pixels} px)" if pixels >= 5 else f"{obj} not seen"
        return SkillResult(True, detail, {"pixels": pixels})

    def _move_object_elsewhere(self, obj: str, furniture: str):
        """Fault: somebody takes the object to another piece of furniture."""
        others = [f for f in self.world.furniture if f != furniture and f in self.furniture_top]
        if not others:
            return
        dest = self.rng.choice(sorted(others))
        self.inject("moved", f"{obj} taken from {furniture} to {dest}")
        used = sum(1 for t, _ in self._resting_objects() if t == dest)
        x, y, z = self._spot_on(dest, used + 1)
        self.p.resetBasePositionAndOrientation(self.body_of[obj], [x, y, z + CAN_HEIGHT / 2 + 0.002],
                                               [0, 0, 0, 1], physicsClientId=self.cid)
        yield from self._settle(0.2)

    @skill("grasp")
    def grasp(self, obj: str, furniture: str):
        """Top grasp at the detected pose: open, descend, close, lift, carry.
        Without a detection (e.g. on a retry) it looks again first."""
        if self.held is not None:
            return SkillResult(False, f"the hand already holds {self.held}")
        if obj not in self.detections:
            yield from self.detect_object(obj, furniture)
        guess = self.detections.get(obj)
        if guess is None:
            return SkillResult(True, f"no detection of {obj} to grasp")
        if self.faults.moved and obj not in self._moved and self.rng.random() < self.faults.moved:
            self._moved.add(obj)   # somebody takes it away once, just before the grasp
            yield from self._move_object_elsewhere(obj, furniture)
        gx, gy, gz = guess
        yield from self._face(gx, gy)
        yaw = self._grasp_yaw(obj)
        self._set_fingers(0.04)
        if not (yield from self._reach([gx, gy, gz + 0.15], 0.8, yaw=yaw)):
            return SkillResult(False, f"{obj} is out of the arm's reach")
        if not (yield from self._reach([gx, gy, gz + 0.01], 0.6, yaw=yaw)):
            return SkillResult(False, f"{obj} is out of the arm's reach")
        yield from self._close_fingers(0.028)
        self._close_on(obj)
        if self.held and self.faults.slip and self.rng.random() < self.faults.slip:
            # it slips just after it leaves the surface, while being lifted
            yield from self._reach([gx, gy, gz + 0.03], 0.2, yaw=yaw)
            self._slip(obj, "gripper")
            yield from self._settle(0.3)
        lift_ok = yield from self._reach([gx, gy, gz + 0.15], 0.5, yaw=yaw)
        yield from self._carry_pose()
        self.detections.pop(obj, None)
        if not lift_ok:
            return SkillResult(False, "could not lift the arm")
        return SkillResult(True, "gripper closed")

    def _grasp_yaw(self, obj: str) -> float:
        """Close the fingers across the object: along the robot's side for an
        upright can, across the axis of a can lying on its side."""
        _, orn = self.p.getBasePositionAndOrientation(self.body_of[obj], physicsClientId=self.cid)
        axis = self.p.getMatrixFromQuaternion(orn)[2::3]   # the cylinder's z axis in the world
        if abs(axis[2]) > 0.7:
            return self.base[2]
        return math.atan2(axis[1], axis[0])

    def _carry_pose(self):
        """Hold the arm (and what it carries) close, to the left of the camera."""
        x, y, yaw = self.base
        mx, my, _ = self._mount_pos()
        lx, ly = -math.sin(yaw), math.cos(yaw)
        fx, fy = math.cos(yaw), math.sin(yaw)
        if not (yield from self._reach([mx + 0.15 * fx + 0.3 * lx, my + 0.15 * fy + 0.3 * ly, 0.9],
                                       0.7)):
            yield from self._move_arm(ARM_HOME, 0.7)
        yield from self._step(24)

    @skill("place_object")
    def place_object(self, obj: str, furniture: str):
        if self.held != obj:
            return SkillResult(True, f"{obj} is not in the hand")
        used = sum(1 for t, _ in self._resting_objects() if t == furniture)
        x, y, z = self._spot_on(furniture, used)
        yield from self._face(x, y)
        if not (yield from self._put_down_at(x, y, z + CAN_HEIGHT / 2, 0.15, 0.015)):
            return SkillResult(False, f"{furniture} is out of the arm's reach")
        yield from self._carry_pose()
        return SkillResult(True, f"released over {furniture}")

    @skill("find_person")
    def find_person(self, person: str):
        if person not in self.world.persons:
            return SkillResult(False, f"unknown person {person}")
        self.seen_persons.pop(person, None)
        x, y, yaw = self.base
        best = 0
        for dyaw in (0.0, 0.7, -0.7):
            look = yaw + dyaw
            target = [x + 2.0 * math.cos(look), y + 2.0 * math.sin(look), 1.0]
            yield from self._turn_to(look)
            best = self._visible_pixels(person, target)
            if best >= 20:
                pos = self._body_pos(person)
                self.seen_persons[person] = (float(pos[0]), float(pos[1]))
                break
        yield from self._turn_to(yaw)
        return SkillResult(True, f"{person} {'seen' if best >= 20 else 'not seen'} ({best} px)")

    @skill("hand_over")
    def hand_over(self, obj: str, person: str):
        if self.held != obj:
            return SkillResult(True, f"{obj} is not in the hand")
        where = self.seen_persons.get(person)
        if where is None:
            return SkillResult(True, f"{person} has not been found")
        px, py = where
        yield from self._face(px, py)
        mx, my, _ = self._mount_pos()
        d = math.hypot(px - mx, py - my)
        reach = min(0.62, max(0.3, d - 0.3))
        ux, uy = (px - mx) / d, (py - my) / d
        if not (yield from self._reach([mx + reach * ux, my + reach * uy, 0.95], 1.0)):
            return SkillResult(False, "cannot extend the arm towards the person")
        ee = self._ee()
        taker = self.world.persons[person]
        if taker.can_receive and math.hypot(ee[0] - px, ee[1] - py) <= HAND_REACH:
            body = self.body_of[obj]
            self._release()
            self._set_fingers(0.04)
            self._give_to(person, body)
        yield from self._step(24)
        yield from self._carry_pose()
        return SkillResult(True, "gripper opened")

    def _give_to(self, person: str, body: int) -> None:
        p, c = self.p, self.cid
        pb = self.body_of[person]
        ppos, porn = p.getBasePositionAndOrientation(pb, physicsClientId=c)
        bpos, born = p.getBasePositionAndOrientation(body, physicsClientId=c)
        inv = p.invertTransform(ppos, porn)
        rel = p.multiplyTransforms(inv[0], inv[1], bpos, born)
        cid = p.createConstraint(pb, -1, body, -1, p.JOINT_FIXED, [0, 0, 0], rel[0], [0, 0, 0],
                                 rel[1], physicsClientId=c)
        self._person_constraints[self.bodies_named[body]] = (person, cid)

    @skill("say")
    def say(self, message: str):
        text = message.replace("_", " ")
        self.spoken.append(message)
        if self.speech is not None:
            self.speech(text)
        yield from self._settle(0.05 * len(text))   # speaking takes time
        return SkillResult(True, f'said "{text}"')

    def hold(self) -> None:
        self._run(self._step(12))

    # ------------------------------------------------------------ checks (monitors)
    def _resting_objects(self) -> list[tuple[str, str]]:
        """(furniture, object) pairs of objects resting on a furniture top."""
        out = []
        p, c = self.p, self.cid
        for t in self.world.things:
            if t not in self.body_of or t == self.held:
                continue
            for f, top in self.furniture_top.items():
                if any(cp[5][2] >= top - 0.02 for cp in p.getContactPoints(
                        bodyA=self.body_of[t], bodyB=self.body_of[f], physicsClientId=c)):
                    out.append((f, t))
                    break
        return out

    @check("on")
    def check_on(self, obj: str, furniture: str) -> Check:
        where = [f for f, t in self._resting_objects() if t == obj]
        ok = furniture in where and self.held != obj
        return Check(ok, f"{obj} rests on {where[0] if where else 'nothing'}")

    @check("handed")
    def check_handed(self, obj: str, person: str) -> Check:
        if obj not in self.body_of or person not in self.body_of:
            return Check(False, "unknown object or person")
        o, q = self._body_pos(obj), self._body_pos(person)
        d = math.hypot(o[0] - q[0], o[1] - q[1])
        holder = self._person_constraints.get(obj, (None,))[0]
        ok = holder == person and d <= HAND_REACH + 0.05 and o[2] > 0.5 and self.held != obj
        return Check(ok, f"{obj} is {d:.2f} m from {person}, {o[2]:.2f} m high")

    @check("person_visible")
    def check_person_visible(self, person: str) -> Check:
        if person not in self.body_of:
            return Check(False, f"no person {person}")
        pos = self._body_pos(person)
        d = math.hypot(pos[0] - self.base[0], pos[1] - self.base[1])
        px = self._visible_pixels(person, [pos[0], pos[1], 1.0])
        ok = person in self.seen_persons and px >= 20 and d <= 3.0
        return Check(ok, f"{person}: {px} px at {d:.2f} m")

    @check("said")
    def check_said(self, message: str) -> Check:
        ok = bool(self.spoken) and self.spoken[-1] == message
        return Check(ok, "spoken" if ok else "not spoken")

    # ------------------------------------------------------------ state estimation
    def observe(self) -> list[tuple[str, tuple]]:
        w = self.world
        facts: list[tuple[str, tuple]] = []
        at = self._place_here()
        if at is None:
            x, y, yaw = self.base
            at = "here"
            facts.append(("location", ("here", round(x, 3), round(y, 3),
                                       round(math.degrees(yaw), 2))))
        facts.append(("robot_at", (w.robot, at)))
        if self.held is not None and self.check_in_gripper(self.held).ok:
            facts.append(("holding", (w.robot, self.held)))
        else:
            facts.append(("free_hand", (w.robot,)))
        for f, t in self._resting_objects():
            facts.append(("object_on", (t, f)))
        for obj, (person, _) in self._person_constraints.items():
            facts.append(("has", (person, obj)))
        return [(p, tuple(float(a) if isinstance(a, (int, float)) else a for a in args))
                for p, args in facts]


__all__ = ["PyBulletRobot", "Faults", "ARM_JOINTS"]
