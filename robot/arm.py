"""A Franka Panda arm mounted on the base, and its parallel gripper.

The arm is kinematic: it follows a straight joint-space interpolation to an
inverse-kinematics solution, one pose per physics step. The gripper holds an
object with a fixed constraint, created only when both fingers really touch
it (:meth:`Arm.close_on`); letting go removes the constraint. A robot with
two arms holds two of them (:mod:`~htn.robot.two_arms`).
"""

from __future__ import annotations

import math

import numpy as np

from .base import MobileBase, Offset
from .faults import FaultDraws
from .interface import Check
from .physics import DT, Physics, yaw_quat

EE_LINK = 11  # panda_grasptarget_hand
FINGERS = (9, 10)
ARM_JOINTS = tuple(range(7))
HAND_LINKS = (*FINGERS, 8, 7, 6)  # links that touch what the hand holds
GRIP_FORCE = 200
HOLD_SLACK = 0.15  # m: a carried object further from its gripper has slipped


class Arm:
    """Reaching and gripping with one arm, mounted on ``base`` at ``offset``."""

    def __init__(
        self,
        physics: Physics,
        base: MobileBase,
        draws: FaultDraws,
        offset: Offset,
        name: str = "arm",
    ):
        self.physics, self.base, self.draws = physics, base, draws
        self.name = name
        p = physics.p
        self.body: int = p.loadURDF(
            "franka_panda/panda.urdf",
            base.mount_pos(offset),
            yaw_quat(p, base.pose[2]),
            useFixedBase=True,
            physicsClientId=physics.cid,
        )
        base.mount(self.body, offset)
        self.held: str | None = None  # what the gripper holds (a constraint)
        self.grip: int | None = None  # that constraint

    def ee(self) -> np.ndarray:
        p, c = self.physics.p, self.physics.cid
        return np.array(p.getLinkState(self.body, EE_LINK, physicsClientId=c)[4])

    def set_fingers(self, width: float) -> None:
        for j in FINGERS:
            self.physics.p.resetJointState(self.body, j, width, physicsClientId=self.physics.cid)

    def q(self) -> list[float]:
        p, c = self.physics.p, self.physics.cid
        return [p.getJointState(self.body, j, physicsClientId=c)[0] for j in ARM_JOINTS]

    def set_q(self, q) -> None:
        for j, v in zip(ARM_JOINTS, q):
            self.physics.p.resetJointState(self.body, j, v, physicsClientId=self.physics.cid)

    def ik(self, pos, down: bool = True, yaw: float | None = None) -> list[float] | None:
        """Joint angles that put the gripper at ``pos`` (pointing down, or
        level), or None if no solution comes within 2 cm."""
        p, c = self.physics.p, self.physics.cid
        yaw = self.base.pose[2] if yaw is None else yaw
        orn = (
            p.getQuaternionFromEuler((math.pi, 0.0, yaw))
            if down
            else p.getQuaternionFromEuler((math.pi / 2, 0.0, yaw - math.pi / 2))
        )
        saved = self.q()
        q = saved
        for _ in range(12):
            q = p.calculateInverseKinematics(
                self.body,
                EE_LINK,
                pos,
                orn,
                maxNumIterations=200,
                residualThreshold=1e-4,
                physicsClientId=c,
            )[:7]
            self.set_q(q)
        err = float(np.linalg.norm(self.ee() - np.array(pos)))
        self.set_q(saved)
        return list(q) if err < 0.02 else None

    def _follow(self, q) -> None:
        """One pose of a motion (an arm kept in place by its joints' commands
        records it, :class:`~htn.robot.two_arms.SideArm`)."""
        self.set_q(q)

    def move(self, q_goal, seconds: float = 1.0):
        q0 = self.q()
        n = max(1, int(seconds / DT))
        for i in range(1, n + 1):
            a = i / n
            self._follow([u + (v - u) * a for u, v in zip(q0, q_goal)])
            yield from self.physics.step()

    def reach(self, pos, seconds: float = 1.0, down: bool = True, yaw: float | None = None):
        """Move the gripper to ``pos``; returns False (without moving) if out of reach."""
        q = self.ik(pos, down, yaw)
        if q is None:
            return False
        yield from self.move(q, seconds)
        return True

    # ------------------------------------------------------------ the gripper
    def close_fingers(self, to: float):
        for w in np.linspace(0.04, to, 12):
            self.set_fingers(float(w))
            yield from self.physics.step(2)

    def fingers_touch(self, body: int) -> bool:
        p, c = self.physics.p, self.physics.cid
        return all(
            p.getContactPoints(bodyA=self.body, bodyB=body, linkIndexA=f, physicsClientId=c)
            for f in FINGERS
        )

    def close_on(self, obj: str) -> bool:
        """Hold ``obj`` if both fingers touch it."""
        body = self.physics.body_of[obj]
        if not self.fingers_touch(body):
            return False
        self.held = obj
        self._attach(body)
        return True

    def _attach(self, body: int) -> None:
        p, c = self.physics.p, self.physics.cid
        ee_pos, ee_orn = p.getLinkState(self.body, EE_LINK, physicsClientId=c)[4:6]
        b_pos, b_orn = p.getBasePositionAndOrientation(body, physicsClientId=c)
        inv_pos, inv_orn = p.invertTransform(ee_pos, ee_orn)
        rel_pos, rel_orn = p.multiplyTransforms(inv_pos, inv_orn, b_pos, b_orn)
        self.grip = p.createConstraint(
            self.body,
            EE_LINK,
            body,
            -1,
            p.JOINT_FIXED,
            [0, 0, 0],
            rel_pos,
            [0, 0, 0],
            rel_orn,
            physicsClientId=c,
        )
        p.changeConstraint(self.grip, maxForce=GRIP_FORCE, physicsClientId=c)
        for link in HAND_LINKS:
            p.setCollisionFilterPair(self.body, body, link, -1, 0, physicsClientId=c)

    def release(self) -> None:
        p, c = self.physics.p, self.physics.cid
        if self.grip is not None:
            p.removeConstraint(self.grip, physicsClientId=c)
            self.grip = None
        if self.held is not None:
            body = self.physics.body_of[self.held]
            for link in HAND_LINKS:
                p.setCollisionFilterPair(self.body, body, link, -1, 1, physicsClientId=c)
        self.held = None

    def put_down_at(self, x: float, y: float, centre: float, above: float, gap: float):
        """The place motion: bring what the hand holds over (x, y), ``above``
        metres higher than where its centre rests (``centre``), lower it to
        ``gap`` above that, let go, and lift the empty hand again. False
        (without moving) if the spot is out of reach."""
        if not (yield from self.reach([x, y, centre + above], 0.8)):
            return False
        yield from self.reach([x, y, centre + gap], 0.6)
        self.release()
        self.set_fingers(0.04)
        yield from self.physics.settle(0.3)
        yield from self.reach([x, y, centre + above], 0.5)
        return True

    def slip(self, obj: str, where: str) -> None:
        """Fault: the object slips out of the gripper."""
        self.draws.inject("slip", f"{obj} slips out of the {where}")
        self.release()
        self.set_fingers(0.04)

    def holds_up(self, obj: str, tolerance: float) -> Check:
        """The effect of a grasp: ``obj``, which this gripper holds, is held up
        by it: close to it (within ``tolerance``), above every table top, and attached."""
        pos = self.physics.body_pos(obj)
        d = float(np.linalg.norm(pos - self.ee()))
        lifted = pos[2] > max(self.physics.furniture_top.values(), default=0.0) + 0.1
        ok = d < tolerance and lifted and self.grip is not None
        return Check(
            ok, f"{obj} is {d:.3f} m from {self.label}" + ("" if lifted else ", not lifted")
        )

    def still_holds(self, obj: str) -> Check:
        """While the robot carries ``obj`` (held by this gripper): still attached
        and near (held objects lag a few centimetres while the base accelerates)."""
        if self.grip is None:
            return Check(False, f"{obj} is in no gripper")
        d = float(np.linalg.norm(self.physics.body_pos(obj) - self.ee()))
        return Check(d < HOLD_SLACK, f"{obj} is {d:.3f} m from the gripper")

    @property
    def label(self) -> str:
        """How messages name this gripper."""
        return "the gripper"
