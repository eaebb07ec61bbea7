"""A simulated domestic robot in PyBullet: a Husky base carrying a Franka Panda.

The world is built from the problem's initial state (:mod:`htn.robot.world`):
tables from ``table/table.urdf``, objects as small cylinders, persons as
upright capsules with a hand point, the robot at its start location.

Motion is kinematic and deterministic: the base (and the arm mounted on it)
moves in small steps of the physics clock, the arm follows joint-space
interpolations to inverse-kinematics solutions. Everything else is physics:
objects fall, rest on surfaces and collide. A grasp holds an object with a
fixed constraint, created only when both fingers really touch it; a person
takes an object the same way when the gripper brings it within reach.

Faults (``slip``, ``nav``, ``detect``, ``moved``) are injected with a seeded
random generator, so the same seed gives the same run.

Each robot keeps an :class:`Odometry`: how far its base and its grippers have
moved, the navigation and manipulation costs that ``htn evaluate --robot
pybullet`` compares.
"""
from __future__ import annotations

import ctypes
import math
import os
import random
import sys
from contextlib import contextmanager
from typing import Optional

import numpy as np

from .faults import Faults
from .interface import Check, Robot, SkillResult
from .world import World

DT = 1.0 / 120.0        # physics step; motion is kinematic, so 120 Hz is stable
BASE_SPEED = 1.0          # m/s
TURN_SPEED = 2.0          # rad/s
POSE_TOLERANCE = 0.05     # m
YAW_TOLERANCE = 0.05      # rad
BASE_Z = 0.14             # husky base height
MOUNT = (0.2, 0.0, 0.48)  # panda base relative to the husky base
EE_LINK = 11              # panda_grasptarget_hand
FINGERS = (9, 10)
ARM_JOINTS = tuple(range(7))
ARM_HOME = (1.5, -0.3, 0.0, -2.6, 0.0, 2.2, 0.785)   # tucked to the left, out of the camera's view
TABLE_TOP = 0.626
CAN_RADIUS, CAN_HEIGHT = 0.033, 0.12
PERSON_RADIUS, PERSON_HEIGHT = 0.2, 1.6
HAND_REACH = 0.7          # a person takes an object within this distance of their axis
CAMERA_HEIGHT = 1.45


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


def _yaw_quat(p, yaw: float):
    return p.getQuaternionFromEuler((0.0, 0.0, yaw))


def _angle_diff(a: float, b: float) -> float:
    return (a - b + math.pi) % (2 * math.pi) - math.pi


class Odometry:
    """Distances travelled, read from the simulation each time the robot's
    clock advances (every base and arm motion of both robots ends that way).

    ``base`` is the path of the base in the plane (m); ``grippers`` the summed
    paths of the gripper frames relative to the base (m), so that driving with
    still arms adds nothing to it. They are the navigation and manipulation
    costs of the plan-transformations paper (Section IV-A: distances between
    key points of the base and gripper trajectories), here measured at every
    physics step of the motion instead of between key points.
    """

    def __init__(self):
        self.base = 0.0
        self.grippers = 0.0
        self._last: Optional[tuple] = None     # base (x, y), grippers in the base frame

    def sample(self, robot: "PyBulletRobot") -> None:
        x, y, yaw = robot.base
        cos, sin = math.cos(yaw), math.sin(yaw)
        grippers = []
        for body, _ in robot._mounted():       # the arms ride on the base
            gx, gy, gz = robot.p.getLinkState(body, EE_LINK, physicsClientId=robot.cid)[4]
            dx, dy = gx - x, gy - y
            grippers.append((cos * dx + sin * dy, cos * dy - sin * dx, gz))
        if self._last is not None:
            (lx, ly), last = self._last
            self.base += math.hypot(x - lx, y - ly)
            self.grippers += sum(math.dist(a, b) for a, b in zip(grippers, last))
        self._last = ((x, y), grippers)


class PyBulletRobot(Robot):
    """The simulated robot; ``gui=True`` opens a window (needs a display)."""

    def __init__(self, world: World, gui: bool = False, faults: Optional[Faults] = None,
                 seed: int = 0, speech=None):
        with quiet_fds():   # importing pybullet prints its build time on fd 1
            import pybullet as p
            import pybullet_data
        self.p = p
        self.world = world
        self.faults = faults or Faults()
        self.rng = random.Random(seed)
        self.odometry: Optional[Odometry] = None     # from when the world is built
        self.sim_time = 0.0
        self.spoken: list[str] = []
        self.injected: list[dict] = []       # faults injected so far (for tests and logs)
        self._moved: set = set()
        self.speech = speech
        self.detections: dict[str, tuple] = {}
        self.seen_persons: dict[str, tuple] = {}
        self.held: Optional[str] = None      # physically attached to the gripper
        self.carrying: Optional[str] = None  # what the robot believes it carries
        self._grip_constraint = None
        self._person_constraints: dict[str, tuple] = {}
        with quiet_fds():
            self.cid = p.connect(p.GUI if gui else p.DIRECT)
            p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=self.cid)
            self._build()
        self.bodies_named = {v: k for k, v in self.body_of.items()}
        self.odometry = Odometry()
        self.odometry.sample(self)

    @property
    def sim_time(self) -> float:
        """Simulated seconds since the world was built."""
        return self._sim_time

    @sim_time.setter
    def sim_time(self, value: float) -> None:
        # both robots' _step advance this clock after every motion increment,
        # so the odometer is read here rather than in each of them
        self._sim_time = value
        if self.odometry is not None:
            self.odometry.sample(self)

    # ------------------------------------------------------------ building
    def _build_ground(self) -> None:
        """Gravity, the clock and the floor; no bodies named yet."""
        p, c = self.p, self.cid
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(DT, physicsClientId=c)
        self.plane = p.loadURDF("plane.urdf", physicsClientId=c)
        self.body_of: dict[str, int] = {}
        self.furniture_top: dict[str, float] = {}

    def _build(self) -> None:
        p, c, w = self.p, self.cid, self.world
        self._build_ground()
        for f in w.furniture.values():
            if f.kind in ("tray",):
                bid = p.loadURDF("tray/traybox.urdf", [f.x, f.y, 0.0], useFixedBase=True,
                                 physicsClientId=c)
            else:
                bid = p.loadURDF("table/table.urdf", [f.x, f.y, 0.0], useFixedBase=True,
                                 physicsClientId=c)
            self.body_of[f.name] = bid
            self.furniture_top[f.name] = p.getAABB(bid, physicsClientId=c)[1][2]
        slots: dict[str, int] = {}
        for t in w.things.values():
            if t.on is None:
                continue
            x, y, z = self._spot_on(t.on, slots.get(t.on, 0))
            slots[t.on] = slots.get(t.on, 0) + 1
            self.body_of[t.name] = self._make_can(x, y, z + CAN_HEIGHT / 2 + 0.002)
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
        self.base = [start.x, start.y, start.theta]
        self.husky = p.loadURDF("husky/husky.urdf", [start.x, start.y, BASE_Z],
                                _yaw_quat(p, start.theta), useFixedBase=True, physicsClientId=c)
        self.arm = p.loadURDF("franka_panda/panda.urdf", self._mount_pos(), _yaw_quat(p, start.theta),
                              useFixedBase=True, physicsClientId=c)
        for j in range(-1, p.getNumJoints(self.husky, physicsClientId=c)):
            for k in range(-1, p.getNumJoints(self.arm, physicsClientId=c)):
                p.setCollisionFilterPair(self.husky, self.arm, j, k, 0, physicsClientId=c)
        for j, q in zip(ARM_JOINTS, ARM_HOME):
            p.resetJointState(self.arm, j, q, physicsClientId=c)
        self._set_fingers(0.04)
        self.body_of[w.robot] = self.husky
        self._settle(0.5)

    def _make_can(self, x: float, y: float, z: float) -> int:
        p, c = self.p, self.cid
        col = p.createCollisionShape(p.GEOM_CYLINDER, radius=CAN_RADIUS, height=CAN_HEIGHT,
                                     physicsClientId=c)
        vis = p.createVisualShape(p.GEOM_CYLINDER, radius=CAN_RADIUS, length=CAN_HEIGHT,
                                  rgbaColor=[0.9, 0.2, 0.1, 1], physicsClientId=c)
        bid = p.createMultiBody(0.15, col, vis, [x, y, z], physicsClientId=c)
        p.changeDynamics(bid, -1, lateralFriction=1.0, physicsClientId=c)
        return bid

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

    # ------------------------------------------------------------ clock
    def _step(self, n: int = 1) -> None:
        for _ in range(n):
            self.p.stepSimulation(physicsClientId=self.cid)
        self.sim_time += n * DT

    def _settle(self, seconds: float) -> None:
        self._step(int(seconds / DT))

    # ------------------------------------------------------------ base
    def _mount_pos(self, base=None):
        x, y, yaw = base or self.base
        return [x + MOUNT[0] * math.cos(yaw) - MOUNT[1] * math.sin(yaw),
                y + MOUNT[0] * math.sin(yaw) + MOUNT[1] * math.cos(yaw), MOUNT[2]]

    def _put_base(self, x: float, y: float, yaw: float) -> None:
        p, c = self.p, self.cid
        yaw = _angle_diff(yaw, 0.0)
        self.base = [x, y, yaw]
        q = _yaw_quat(p, yaw)
        p.resetBasePositionAndOrientation(self.husky, [x, y, BASE_Z], q, physicsClientId=c)
        for body, pos in self._mounted():
            p.resetBasePositionAndOrientation(body, pos, q, physicsClientId=c)

    def _mounted(self) -> list:
        """(body, position) of what is mounted on the base, for its current pose."""
        return [(self.arm, self._mount_pos())]

    def _speeds(self) -> tuple[float, float]:
        """Base speed (m/s) and turning speed (rad/s)."""
        return BASE_SPEED, TURN_SPEED

    @staticmethod
    def _ramp(k: float) -> float:
        """Fraction of a base motion done after fraction ``k`` of its time."""
        return k

    def _turn_to(self, yaw: float) -> bool:
        x, y, start = self.base
        delta = _angle_diff(yaw, start)
        n = max(1, int(abs(delta) / (self._speeds()[1] * DT)))
        for i in range(1, n + 1):
            self._put_base(x, y, start + delta * self._ramp(i / n))
            self._step()
            if i % 12 == 0 and self._base_contacts():
                return False
        return True

    def _drive(self, gx: float, gy: float, fraction: float = 1.0) -> bool:
        x0, y0, yaw = self.base
        dist = math.hypot(gx - x0, gy - y0) * fraction
        n = max(1, int(dist / (self._speeds()[0] * DT)))
        ux, uy = (gx - x0), (gy - y0)
        norm = math.hypot(ux, uy) or 1.0
        ux, uy = ux / norm, uy / norm
        for i in range(1, n + 1):
            d = dist * self._ramp(i / n)
            self._put_base(x0 + ux * d, y0 + uy * d, yaw)
            self._step()
            if i % 12 == 0 and self._base_contacts():
                return False
        return True

    def _face(self, x: float, y: float) -> bool:
        return self._turn_to(math.atan2(y - self.base[1], x - self.base[0]))

    def _base_contacts(self) -> list[str]:
        """Names of bodies the base or arm touches (the floor and held objects excepted)."""
        p, c = self.p, self.cid
        names = []
        for body in (self.husky, self.arm):
            for cp in p.getContactPoints(bodyA=body, physicsClientId=c):
                other = cp[2]
                if other in (self.plane, self.husky, self.arm):
                    continue
                if self.held is not None and other == self.body_of.get(self.held):
                    continue
                names.append(self.bodies_named.get(other, str(other)))
        return sorted(set(names))

    # ------------------------------------------------------------ arm
    def _ee(self) -> np.ndarray:
        return np.array(self.p.getLinkState(self.arm, EE_LINK, physicsClientId=self.cid)[4])

    def _set_fingers(self, width: float) -> None:
        for j in FINGERS:
            self.p.resetJointState(self.arm, j, width, physicsClientId=self.cid)

    def _arm_q(self) -> list[float]:
        return [self.p.getJointState(self.arm, j, physicsClientId=self.cid)[0] for j in ARM_JOINTS]

    def _ik(self, pos, down: bool = True, yaw: Optional[float] = None) -> Optional[list[float]]:
        p, c = self.p, self.cid
        yaw = self.base[2] if yaw is None else yaw
        orn = p.getQuaternionFromEuler((math.pi, 0.0, yaw)) if down else \
            p.getQuaternionFromEuler((math.pi / 2, 0.0, yaw - math.pi / 2))
        saved = self._arm_q()
        q = saved
        for _ in range(12):
            q = p.calculateInverseKinematics(self.arm, EE_LINK, pos, orn, maxNumIterations=200,
                                             residualThreshold=1e-4, physicsClientId=c)[:7]
            for j, v in zip(ARM_JOINTS, q):
                p.resetJointState(self.arm, j, v, physicsClientId=c)
        err = float(np.linalg.norm(self._ee() - np.array(pos)))
        for j, v in zip(ARM_JOINTS, saved):
            p.resetJointState(self.arm, j, v, physicsClientId=c)
        return list(q) if err < 0.02 else None

    def _move_arm(self, q_goal, seconds: float = 1.0) -> None:
        q0 = self._arm_q()
        n = max(1, int(seconds / DT))
        for i in range(1, n + 1):
            a = i / n
            for j, u, v in zip(ARM_JOINTS, q0, q_goal):
                self.p.resetJointState(self.arm, j, u + (v - u) * a, physicsClientId=self.cid)
            self._step()

    def _reach(self, pos, seconds: float = 1.0, down: bool = True,
               yaw: Optional[float] = None) -> bool:
        q = self._ik(pos, down, yaw)
        if q is None:
            return False
        self._move_arm(q, seconds)
        return True

    def _attach(self, body: int) -> None:
        p, c = self.p, self.cid
        ee_pos, ee_orn = p.getLinkState(self.arm, EE_LINK, physicsClientId=c)[4:6]
        b_pos, b_orn = p.getBasePositionAndOrientation(body, physicsClientId=c)
        inv_pos, inv_orn = p.invertTransform(ee_pos, ee_orn)
        rel_pos, rel_orn = p.multiplyTransforms(inv_pos, inv_orn, b_pos, b_orn)
        self._grip_constraint = p.createConstraint(self.arm, EE_LINK, body, -1, p.JOINT_FIXED,
                                                   [0, 0, 0], rel_pos, [0, 0, 0], rel_orn,
                                                   physicsClientId=c)
        p.changeConstraint(self._grip_constraint, maxForce=200, physicsClientId=c)
        for link in (*FINGERS, 8, 7, 6):
            p.setCollisionFilterPair(self.arm, body, link, -1, 0, physicsClientId=c)

    def _release(self) -> None:
        p, c = self.p, self.cid
        if self._grip_constraint is not None:
            p.removeConstraint(self._grip_constraint, physicsClientId=c)
            self._grip_constraint = None
        if self.held is not None:
            body = self.body_of[self.held]
            for link in (*FINGERS, 8, 7, 6):
                p.setCollisionFilterPair(self.arm, body, link, -1, 1, physicsClientId=c)
        self.held = None

    def _fingers_touch(self, body: int) -> bool:
        p, c = self.p, self.cid
        return all(p.getContactPoints(bodyA=self.arm, bodyB=body, linkIndexA=f, physicsClientId=c)
                   for f in FINGERS)

    def _body_pos(self, name: str) -> np.ndarray:
        return np.array(self.p.getBasePositionAndOrientation(self.body_of[name],
                                                            physicsClientId=self.cid)[0])

    # ------------------------------------------------------------ perception
    CAMERA_PIXELS = (96, 72)   # width, height of the head camera's image

    def _visible_pixels(self, name: str, target) -> int:
        """Pixels of ``name`` in the head camera's segmentation image, looking at ``target``."""
        p, c = self.p, self.cid
        x, y, _ = self.base
        w_, h_ = self.CAMERA_PIXELS
        eye = [x + 0.1 * math.cos(self.base[2]), y + 0.1 * math.sin(self.base[2]), CAMERA_HEIGHT]
        view = p.computeViewMatrix(eye, list(target), [0, 0, 1], physicsClientId=c)
        proj = p.computeProjectionMatrixFOV(70, 4 / 3, 0.1, 8.0, physicsClientId=c)
        img = p.getCameraImage(w_, h_, view, proj, renderer=p.ER_TINY_RENDERER,
                               physicsClientId=c)
        seg = np.asarray(img[4]).reshape(h_, w_)
        return int(np.count_nonzero((seg & ((1 << 24) - 1)) == self.body_of[name]))

    def _noisy_pos(self, name: str) -> tuple:
        """Where perception puts a body: its position with a few millimetres of noise."""
        return tuple(self._body_pos(name) + np.array(
            [self.rng.gauss(0, 0.003), self.rng.gauss(0, 0.003), 0]))

    def _nav_fault(self, place: str) -> float:
        """The fraction of the way to ``place`` a drive gets (1.0 without a fault)."""
        if self.faults.nav and self.rng.random() < self.faults.nav:
            fraction = self.rng.uniform(0.4, 0.85)
            self._inject("nav", f"stops at {fraction:.0%} of the way to {place}")
            return fraction
        return 1.0

    # ------------------------------------------------------------ skills
    def move_base(self, place: str) -> SkillResult:
        goal = self.world.place(place)
        fraction = self._nav_fault(place)
        if math.hypot(goal.x - self.base[0], goal.y - self.base[1]) > 1e-3:
            if not self._face(goal.x, goal.y):
                return SkillResult(True, "bumped into something while turning")
            if not self._drive(goal.x, goal.y, fraction):
                return SkillResult(True, "bumped into something while driving")
        if fraction == 1.0 and not self._turn_to(goal.theta):
            return SkillResult(True, "bumped into something while turning")
        self._step(12)
        return SkillResult(True, f"stopped at {self.base[0]:.2f} {self.base[1]:.2f}")

    def detect_object(self, obj: str, furniture: str) -> SkillResult:
        self.detections.pop(obj, None)
        if obj not in self.body_of or furniture not in self.body_of:
            return SkillResult(False, f"unknown object or furniture {obj}/{furniture}")
        target = self._body_pos(furniture)
        target[2] = self.furniture_top[furniture]
        self._face(target[0], target[1])
        pixels = self._look(obj, target)
        detail = f"{obj} seen ({pixels} px)" if pixels >= 5 else f"{obj} not seen"
        return SkillResult(True, detail, {"pixels": pixels})

    def _look(self, obj: str, target) -> int:
        """Look at ``target`` for ``obj``; record a detection when it is seen
        (5 pixels or more). Returns the pixels (0 after a detection fault)."""
        pixels = self._visible_pixels(obj, target)
        if self.faults.detect and self.rng.random() < self.faults.detect:
            pixels = 0
            self._inject("detect", f"{obj} missed")
        if pixels >= 5:
            self.detections[obj] = self._noisy_pos(obj)
        return pixels

    def _inject(self, fault: str, detail: str) -> None:
        self.injected.append({"fault": fault, "t": round(self.sim_time, 4), "detail": detail})

    def has_detection(self, obj: str) -> bool:
        return obj in self.detections

    def _move_object_elsewhere(self, obj: str, furniture: str) -> None:
        """Fault: somebody takes the object to another piece of furniture."""
        others = [f for f in self.world.furniture if f != furniture and f in self.furniture_top]
        if not others:
            return
        dest = self.rng.choice(sorted(others))
        self._inject("moved", f"{obj} taken from {furniture} to {dest}")
        used = sum(1 for t, _ in self._resting_objects() if t == dest)
        x, y, z = self._spot_on(dest, used + 1)
        self.p.resetBasePositionAndOrientation(self.body_of[obj], [x, y, z + CAN_HEIGHT / 2 + 0.002],
                                               [0, 0, 0, 1], physicsClientId=self.cid)
        self._settle(0.2)

    def grasp(self, obj: str, furniture: str) -> SkillResult:
        """Top grasp at the detected pose: open, descend, close, lift, carry."""
        if self.held is not None:
            return SkillResult(False, f"the hand already holds {self.held}")
        guess = self.detections.get(obj)
        if guess is None:
            return SkillResult(True, f"no detection of {obj} to grasp")
        if self.faults.moved and obj not in self._moved and self.rng.random() < self.faults.moved:
            self._moved.add(obj)   # somebody takes it away once, just before the grasp
            self._move_object_elsewhere(obj, furniture)
        gx, gy, gz = guess
        self._face(gx, gy)
        yaw = self._grasp_yaw(obj)
        self._set_fingers(0.04)
        if not self._reach([gx, gy, gz + 0.15], 0.8, yaw=yaw):
            return SkillResult(False, f"{obj} is out of the arm's reach")
        if not self._reach([gx, gy, gz + 0.01], 0.6, yaw=yaw):
            return SkillResult(False, f"{obj} is out of the arm's reach")
        for w_ in np.linspace(0.04, 0.028, 12):
            self._set_fingers(float(w_))
            self._step(2)
        body = self.body_of[obj]
        self.carrying = None
        if self._fingers_touch(body):
            self.held = self.carrying = obj
            self._attach(body)
        if self.held and self.faults.slip and self.rng.random() < self.faults.slip:
            # it slips just after it leaves the surface, while being lifted
            self._reach([gx, gy, gz + 0.03], 0.2, yaw=yaw)
            self._inject("slip", f"{obj} slips out of the gripper")
            self._release()
            self._set_fingers(0.04)
            self._settle(0.3)
        lift_ok = self._reach([gx, gy, gz + 0.15], 0.5, yaw=yaw)
        self._carry_pose()
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

    def _carry_pose(self) -> None:
        """Hold the arm (and what it carries) close, to the left of the camera."""
        x, y, yaw = self.base
        mx, my, _ = self._mount_pos()
        lx, ly = -math.sin(yaw), math.cos(yaw)
        fx, fy = math.cos(yaw), math.sin(yaw)
        if not self._reach([mx + 0.15 * fx + 0.3 * lx, my + 0.15 * fy + 0.3 * ly, 0.9], 0.7):
            self._move_arm(ARM_HOME, 0.7)
        self._step(24)

    def place_object(self, obj: str, furniture: str) -> SkillResult:
        if self.held != obj:
            return SkillResult(True, f"{obj} is not in the hand")
        used = sum(1 for t, _ in self._resting_objects() if t == furniture)
        x, y, z = self._spot_on(furniture, used)
        self._face(x, y)
        if not self._reach([x, y, z + CAN_HEIGHT / 2 + 0.15], 0.8):
            return SkillResult(False, f"{furniture} is out of the arm's reach")
        self._reach([x, y, z + CAN_HEIGHT / 2 + 0.015], 0.6)
        self._release()
        self.carrying = None
        self._set_fingers(0.04)
        self._settle(0.3)
        self._reach([x, y, z + CAN_HEIGHT / 2 + 0.15], 0.5)
        self._carry_pose()
        return SkillResult(True, f"released over {furniture}")

    def find_person(self, person: str) -> SkillResult:
        if person not in self.world.persons:
            return SkillResult(False, f"unknown person {person}")
        self.seen_persons.pop(person, None)
        x, y, yaw = self.base
        best = 0
        for dyaw in (0.0, 0.7, -0.7):
            look = yaw + dyaw
            target = [x + 2.0 * math.cos(look), y + 2.0 * math.sin(look), 1.0]
            self._turn_to(look)
            best = self._visible_pixels(person, target)
            if best >= 20:
                pos = self._body_pos(person)
                self.seen_persons[person] = (float(pos[0]), float(pos[1]))
                break
        self._turn_to(yaw)
        return SkillResult(True, f"{person} {'seen' if best >= 20 else 'not seen'} ({best} px)")

    def hand_over(self, obj: str, person: str) -> SkillResult:
        if self.held != obj:
            return SkillResult(True, f"{obj} is not in the hand")
        where = self.seen_persons.get(person)
        if where is None:
            return SkillResult(True, f"{person} has not been found")
        px, py = where
        self._face(px, py)
        mx, my, _ = self._mount_pos()
        d = math.hypot(px - mx, py - my)
        reach = min(0.62, max(0.3, d - 0.3))
        ux, uy = (px - mx) / d, (py - my) / d
        if not self._reach([mx + reach * ux, my + reach * uy, 0.95], 1.0):
            return SkillResult(False, "cannot extend the arm towards the person")
        ee = self._ee()
        taker = self.world.persons[person]
        if taker.can_receive and math.hypot(ee[0] - px, ee[1] - py) <= HAND_REACH:
            body = self.body_of[obj]
            self._release()
            self.carrying = None
            self._set_fingers(0.04)
            self._give_to(person, body)
        self._step(24)
        self._carry_pose()
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

    def say(self, message: str) -> SkillResult:
        text = message.replace("_", " ")
        self.spoken.append(message)
        if self.speech is not None:
            self.speech(text)
        self._step(int(0.05 * len(text) / DT))   # speaking takes time
        return SkillResult(True, f'said "{text}"')

    def hold(self) -> None:
        self._step(12)

    # ------------------------------------------------------------ checks (monitors)
    def check_base_at(self, place: str) -> Check:
        goal = self.world.place(place)
        x, y, _ = self.husky_pose()
        yaw = self.base[2]
        err = math.hypot(goal.x - x, goal.y - y)
        yaw_err = abs(_angle_diff(goal.theta, yaw))
        ok = err <= POSE_TOLERANCE and yaw_err <= YAW_TOLERANCE
        return Check(ok, f"{err:.3f} m, {yaw_err:.3f} rad from {place}")

    def husky_pose(self):
        pos, _ = self.p.getBasePositionAndOrientation(self.husky, physicsClientId=self.cid)
        return pos

    def check_no_collision(self) -> Check:
        hits = self._base_contacts()
        return Check(not hits, "touching " + ", ".join(hits) if hits else "no contact")

    def check_in_gripper(self, obj: str) -> Check:
        if obj not in self.body_of:
            return Check(False, f"no object {obj}")
        d = float(np.linalg.norm(self._body_pos(obj) - self._ee()))
        lifted = self._body_pos(obj)[2] > max(self.furniture_top.values(), default=0.0) + 0.1
        ok = d < 0.05 and lifted and self._grip_constraint is not None
        return Check(ok, f"{obj} is {d:.3f} m from the gripper" + ("" if lifted else ", not lifted"))

    def _resting_objects(self) -> list[tuple[str, str]]:
        """(furniture, object) pairs of objects resting on a furniture top."""
        out = []
        p, c = self.p, self.cid
        for t in self.world.things:
            if t not in self.body_of or t == self.held:
                continue
            for f, top in self.furniture_top.items():
                for cp in p.getContactPoints(bodyA=self.body_of[t], bodyB=self.body_of[f],
                                             physicsClientId=c):
                    if cp[5][2] >= top - 0.02:
                        out.append((f, t))
                        break
                else:
                    continue
                break
        return out

    def check_on(self, obj: str, furniture: str) -> Check:
        where = [f for f, t in self._resting_objects() if t == obj]
        ok = furniture in where and self.held != obj
        return Check(ok, f"{obj} rests on {where[0] if where else 'nothing'}")

    def check_handed(self, obj: str, person: str) -> Check:
        if obj not in self.body_of or person not in self.body_of:
            return Check(False, "unknown object or person")
        o, q = self._body_pos(obj), self._body_pos(person)
        d = math.hypot(o[0] - q[0], o[1] - q[1])
        holder = self._person_constraints.get(obj, (None,))[0]
        ok = holder == person and d <= HAND_REACH + 0.05 and o[2] > 0.5 and self.held != obj
        return Check(ok, f"{obj} is {d:.2f} m from {person}, {o[2]:.2f} m high")

    def check_person_visible(self, person: str) -> Check:
        if person not in self.body_of:
            return Check(False, f"no person {person}")
        pos = self._body_pos(person)
        d = math.hypot(pos[0] - self.base[0], pos[1] - self.base[1])
        target = [pos[0], pos[1], 1.0]
        px = self._visible_pixels(person, target)
        ok = person in self.seen_persons and px >= 20 and d <= 3.0
        return Check(ok, f"{person}: {px} px at {d:.2f} m")

    def check_detection(self, obj: str) -> Check:
        det = self.detections.get(obj)
        if det is None:
            return Check(False, f"no detection of {obj}")
        err = float(np.linalg.norm(np.array(det) - self._body_pos(obj)))
        return Check(err < 0.03, f"detection {err:.3f} m from {obj}")

    def check_said(self, message: str) -> Check:
        ok = bool(self.spoken) and self.spoken[-1] == message
        return Check(ok, "spoken" if ok else "not spoken")

    # ------------------------------------------------------------ state estimation
    def observe(self) -> list[tuple[str, tuple]]:
        w = self.world
        facts: list[tuple[str, tuple]] = []
        x, y, yaw = self.base
        at = None
        for pl in w.places.values():
            if math.hypot(pl.x - x, pl.y - y) <= POSE_TOLERANCE and \
                    abs(_angle_diff(pl.theta, yaw)) <= YAW_TOLERANCE:
                at = pl.name
                break
        if at is None:
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

    # ------------------------------------------------------------ output
    def snapshot(self, path: str) -> Optional[str]:
        """Save a PNG from an overview camera following the robot."""
        p, c = self.p, self.cid
        x, y, yaw = self.base
        eye = [x - 2.2 * math.cos(yaw) + 0.8, y - 2.2 * math.sin(yaw) - 0.8, 2.6]
        view = p.computeViewMatrix(eye, [x + 0.6 * math.cos(yaw), y + 0.6 * math.sin(yaw), 0.5],
                                   [0, 0, 1], physicsClientId=c)
        proj = p.computeProjectionMatrixFOV(60, 4 / 3, 0.1, 20, physicsClientId=c)
        w_, h_, rgb, _, _ = p.getCameraImage(480, 360, view, proj, renderer=p.ER_TINY_RENDERER,
                                             physicsClientId=c)
        from PIL import Image
        arr = np.asarray(rgb, dtype=np.uint8).reshape(h_, w_, 4)[:, :, :3]
        Image.fromarray(arr).save(path)
        return path

    def close(self) -> None:
        try:
            self.p.disconnect(physicsClientId=self.cid)
        except Exception:  # already disconnected
            pass
