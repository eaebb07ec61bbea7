"""A tray of the kitchen: a light box with rims, carried with both hands.

Objects go on it with one hand and ride on it by friction while it is
carried. Lifted, the tray follows the left hand through a constraint (its
pose relative to that hand is kept, step by step) while the right hand keeps
its side. The base drives slower with it (see the kitchen robot's ``_speeds``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

from .arm import EE_LINK, FINGERS
from .interface import Check, SkillResult, check, skill
from .physics import yaw_quat

TRAY_HALF = (0.13, 0.17, 0.045)     # half depth (u), half width (v), rim height
TRAY_U = 0.88                       # where it stands on a table, in its area's frame
TRAY_SPOTS = ((-0.06, 0.06), (-0.06, -0.06), (0.06, 0.06), (0.06, -0.06))
SIDE = {"left": 1.0, "right": -1.0}


@dataclass
class Hold:
    """The tray in both hands: it follows the left hand with this offset."""
    tray: str
    constraint: int
    rel: tuple
    riders: tuple = ()              # what stood on the tray when it was lifted


class Trays:
    """The kitchen robot's part for trays."""

    hold_tray: Optional[Hold] = None

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

    def _tray_discs(self, u: float, v: float) -> list[tuple[float, float, float]]:
        """Four discs (u, v, radius) covering a tray centred at (u, v) of an area."""
        return [(u + du, v + dv, 0.12) for du in (-0.07, 0.07) for dv in (-0.09, 0.09)]

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

    def _follow_tray(self) -> None:
        """Keep the carried tray where the left hand holds it (every physics step)."""
        p, c = self.p, self.cid
        ee_pos, ee_orn = p.getLinkState(self.arm_body["left"], EE_LINK, physicsClientId=c)[4:6]
        pos, orn = p.multiplyTransforms(ee_pos, ee_orn, *self.hold_tray.rel)
        p.changeConstraint(self.hold_tray.constraint, jointChildPivot=pos,
                           jointChildFrameOrientation=orn, maxForce=300, physicsClientId=c)

    # ------------------------------------------------------------ skills
    @skill("put_on_tray")
    def put_on_tray(self, obj: str, tray: str, arm: Optional[str] = None):
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
                    return (yield from self._put_down(obj, x, y, tpos[2] + 0.008, f"{tray}"))
        return SkillResult(False, f"no free spot on {tray} within the {arm} arm's reach")

    @skill("take_from_tray")
    def take_from_tray(self, obj: str, tray: str, arm: Optional[str] = None):
        arm = self._pick_arm(arm)
        if arm is None or self.arm_held[arm] is not None:
            return SkillResult(False, f"the {arm or 'robot'}'s hand is not free")
        if tray not in self.trays or obj not in self.body_of:
            return SkillResult(False, f"unknown tray or object {tray}/{obj}")
        if self._visible_pixels(obj, list(self._body_pos(tray))) < 5:
            return SkillResult(True, f"{obj} is not seen on {tray}")
        with self._using(arm):
            return (yield from self._top_grasp(obj, self._noisy_pos(obj)))

    def _rims(self, pos, orn) -> dict:
        """Where each hand holds the tray (posed at pos, orn): the middle of its side rim."""
        hv = TRAY_HALF[1] - 0.004
        z = TRAY_HALF[2] - 0.01
        return {a: list(self.p.multiplyTransforms(pos, orn, [0, SIDE[a] * hv, z],
                                                  [0, 0, 0, 1])[0]) for a in self.ARMS}

    @skill("lift_tray")
    def lift_tray(self, tray: str):
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
                yield from self._home_both()
                return SkillResult(False, f"{tray} is out of reach of both arms")
            yield from self._move_arms(qs, 0.8)
        self._hands_touch_tray(bid, False)   # they hold its rims: no contact forces
        for a in self.ARMS:
            self._set_fingers_of(a, 0.004)
        yield from self._step(6)
        ee_pos, ee_orn = p.getLinkState(self.arm_body["left"], EE_LINK, physicsClientId=c)[4:6]
        inv = p.invertTransform(ee_pos, ee_orn)
        rel = p.multiplyTransforms(inv[0], inv[1], pos, orn)
        cid = p.createConstraint(bid, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0], pos,
                                 childFrameOrientation=orn, physicsClientId=c)
        self.hold_tray = Hold(tray, cid, rel, tuple(self._on_tray(tray)))
        goals = {a: self._ik_for(a, lifted[a]) for a in self.ARMS}
        if any(q is None for q in goals.values()):
            yield from self._let_go_of_tray()
            return SkillResult(False, f"the arms cannot lift {tray}")
        yield from self._move_arms(goals, 1.0)
        yield from self._step(24)
        return SkillResult(True, f"{tray} lifted with both hands")

    @skill("lower_tray")
    def lower_tray(self, tray: str, where: str):
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
            pos, orn = [x, y, top + 0.004], yaw_quat(p, yaw)
            rims = self._rims(pos, orn)
            ee_goal = p.multiplyTransforms(pos, orn, *p.invertTransform(*self.hold_tray.rel))[0]
            left = self._ik_for("left", ee_goal)
            right = self._ik_for("right", [*rims["right"][:2], ee_goal[2]])
            if left is not None and right is not None:
                break
        else:
            return SkillResult(False, f"no free place for {tray} within reach on {where}")
        yield from self._move_arms({"left": left, "right": right}, 1.2)
        yield from self._let_go_of_tray()
        yield from self._home_both()
        return SkillResult(True, f"{tray} lowered onto {where}")

    def _hands_touch_tray(self, tray_body: int, touch: bool) -> None:
        for a in self.ARMS:
            for link in (*FINGERS, 8, 7, 6):
                self.p.setCollisionFilterPair(self.arm_body[a], tray_body, link, -1, int(touch),
                                              physicsClientId=self.cid)

    def _let_go_of_tray(self):
        """Release the tray where it is: let it settle, open and raise both hands."""
        bid = self.trays[self.hold_tray.tray]
        self.p.removeConstraint(self.hold_tray.constraint, physicsClientId=self.cid)
        self.hold_tray = None
        yield from self._settle(0.3)
        for a in self.ARMS:
            self._set_fingers_of(a, 0.04)
        ups = {a: self._ik_for(a, [*self._ee_of(a)[:2], self._ee_of(a)[2] + 0.1]) for a in self.ARMS}
        yield from self._move_arms({a: q for a, q in ups.items() if q is not None}, 0.4)
        self._hands_touch_tray(bid, True)

    # ------------------------------------------------------------ checks
    @check("on_tray")
    def check_on_tray(self, obj: str, tray: str) -> Check:
        if tray not in self.trays or obj not in self.body_of:
            return Check(False, f"unknown tray or object {tray}/{obj}")
        ok = obj in self._on_tray(tray)
        return Check(ok, f"{obj} {'rests' if ok else 'does not rest'} on {tray}")

    @check("tray_carried")
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
