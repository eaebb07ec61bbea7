"""A Franka Panda arm mounted on the base, and its parallel gripper.

The arm is kinematic: it follows a straight joint-space interpolation to an
inverse-kinematics solution, one pose per physics step. The gripper holds an
object with a fixed constraint, created only when both fingers really touch
it (:meth:`Arm._close_on`); letting go removes the constraint. A robot with
several arms runs these helpers on the selected one (``self.arm``).
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .interface import Check, check
from .physics import DT

EE_LINK = 11              # panda_grasptarget_hand
FINGERS = (9, 10)
ARM_JOINTS = tuple(range(7))
HAND_LINKS = (*FINGERS, 8, 7, 6)   # links that touch what the hand holds
GRIP_FORCE = 200
HOLD_SLACK = 0.15         # m: a carried object further from its gripper has slipped


class Arm:
    """Reaching and gripping with the selected arm (``self.arm``)."""

    held: Optional[str] = None           # what the selected gripper holds (a constraint)
    _grip_constraint: Optional[int] = None

    def _ee(self) -> np.ndarray:
        return np.array(self.p.getLinkState(self.arm, EE_LINK, physicsClientId=self.cid)[4])

    def _set_fingers(self, width: float) -> None:
        for j in FINGERS:
            self.p.resetJointState(self.arm, j, width, physicsClientId=self.cid)

    def _arm_q(self) -> list[float]:
        return [self.p.getJointState(self.arm, j, physicsClientId=self.cid)[0] for j in ARM_JOINTS]

    def _set_arm_q(self, q) -> None:
        for j, v in zip(ARM_JOINTS, q):
            self.p.resetJointState(self.arm, j, v, physicsClientId=self.cid)

    def _ik(self, pos, down: bool = True, yaw: Optional[float] = None) -> Optional[list[float]]:
        """Joint angles that put the gripper at ``pos`` (pointing down, or
        level), or None if no solution comes within 2 cm."""
        p, c = self.p, self.cid
        yaw = self.base[2] if yaw is None else yaw
        orn = p.getQuaternionFromEuler((math.pi, 0.0, yaw)) if down else \
            p.getQuaternionFromEuler((math.pi / 2, 0.0, yaw - math.pi / 2))
        saved = self._arm_q()
        q = saved
        for _ in range(12):
            q = p.calculateInverseKinematics(self.arm, EE_LINK, pos, orn, maxNumIterations=200,
                                             residualThreshold=1e-4, physicsClientId=c)[:7]
            self._set_arm_q(q)
        err = float(np.linalg.norm(self._ee() - np.array(pos)))
        self._set_arm_q(saved)
        return list(q) if err < 0.02 else None

    def _move_arm(self, q_goal, seconds: float = 1.0):
        q0 = self._arm_q()
        n = max(1, int(seconds / DT))
        for i in range(1, n + 1):
            a = i / n
            self._set_arm_q([u + (v - u) * a for u, v in zip(q0, q_goal)])
            yield from self._step()

    def _reach(self, pos, seconds: float = 1.0, down: bool = True, yaw: Optional[float] = None):
        """Move the gripper to ``pos``; returns False (without moving) if out of reach."""
        q = self._ik(pos, down, yaw)
        if q is None:
            return False
        yield from self._move_arm(q, seconds)
        return True

    # ------------------------------------------------------------ the gripper
    def _close_fingers(self, to: float):
        for w in np.linspace(0.04, to, 12):
            self._set_fingers(float(w))
            yield from self._step(2)

    def _fingers_touch(self, body: int) -> bool:
        p, c = self.p, self.cid
        return all(p.getContactPoints(bodyA=self.arm, bodyB=body, linkIndexA=f, physicsClientId=c)
                   for f in FINGERS)

    def _close_on(self, obj: str) -> bool:
        """Hold ``obj`` if both fingers touch it."""
        body = self.body_of[obj]
        if not self._fingers_touch(body):
            return False
        self.held = obj
        self._attach(body)
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
        p.changeConstraint(self._grip_constraint, maxForce=GRIP_FORCE, physicsClientId=c)
        for link in HAND_LINKS:
            p.setCollisionFilterPair(self.arm, body, link, -1, 0, physicsClientId=c)

    def _release(self) -> None:
        p, c = self.p, self.cid
        if self._grip_constraint is not None:
            p.removeConstraint(self._grip_constraint, physicsClientId=c)
            self._grip_constraint = None
        if self.held is not None:
            body = self.body_of[self.held]
            for link in HAND_LINKS:
                p.setCollisionFilterPair(self.arm, body, link, -1, 1, physicsClientId=c)
        self.held = None

    def _put_down_at(self, x: float, y: float, centre: float, above: float, gap: float):
        """The place motion: bring what the hand holds over (x, y), ``above``
        metres higher than where its centre rests (``centre``), lower it to
        ``gap`` above that, let go, and lift the empty hand again. False
        (without moving) if the spot is out of reach."""
        if not (yield from self._reach([x, y, centre + above], 0.8)):
            return False
        yield from self._reach([x, y, centre + gap], 0.6)
        self._release()
        self._set_fingers(0.04)
        yield from self._settle(0.3)
        yield from self._reach([x, y, centre + above], 0.5)
        return True

    def _slip(self, obj: str, where: str) -> None:
        """Fault: the object slips out of the selected gripper."""
        self.inject("slip", f"{obj} slips out of the {where}")
        self._release()
        self._set_fingers(0.04)

    # how far a held object's centre may be from the gripper for a grasp to count
    GRIP_TOLERANCE = 0.05

    def _gripper_of(self, obj: str):
        """(gripper position, its constraint, its name) of the gripper holding
        ``obj``, or None."""
        if self.held != obj:
            return None
        return self._ee(), self._grip_constraint, "the gripper"

    @check("in_gripper")
    def check_in_gripper(self, obj: str) -> Check:
        """The effect of a grasp: the object is held up by the gripper holding
        it: close to it, above every table top, and attached."""
        if obj not in self.body_of:
            return Check(False, f"no object {obj}")
        grip = self._gripper_of(obj)
        if grip is None:
            return Check(False, f"{obj} is in no gripper")
        ee, constraint, name = grip
        pos = self._body_pos(obj)
        d = float(np.linalg.norm(pos - ee))
        lifted = pos[2] > max(self.furniture_top.values(), default=0.0) + 0.1
        ok = d < self.GRIP_TOLERANCE and lifted and constraint is not None
        return Check(ok, f"{obj} is {d:.3f} m from {name}" + ("" if lifted else ", not lifted"))

    @check("still_held")
    def check_still_held(self, obj: str) -> Check:
        """While the robot carries ``obj``: still attached to its gripper and
        near it (held objects lag a few centimetres while the base accelerates)."""
        grip = self._gripper_of(obj) if obj in self.body_of else None
        if grip is None or grip[1] is None:
            return Check(False, f"{obj} is in no gripper")
        d = float(np.linalg.norm(self._body_pos(obj) - grip[0]))
        return Check(d < HOLD_SLACK, f"{obj} is {d:.3f} m from the gripper")
