"""A tray of the kitchen: a light box with rims, carried with both hands.

Objects go on it with one hand and ride on it by friction while it is
carried. Lifted, the tray follows the left hand through a constraint (its
pose relative to that hand is kept, step by step) while the right hand keeps
its side. The base drives slower with it (see the kitchen robot's
``_limits``). The bodies are made while the world is built
(:func:`make_tray`), before the arms that carry them exist; the
:class:`Trays` part acts on them afterwards.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from .areas import AreaFrames
from .arm import EE_LINK, FINGERS
from .base import MobileBase
from .interface import Check, SkillResult
from .physics import Physics, open_box, yaw_quat
from .two_arms import SIDE, TwoArms
from .world import World

Footprints = Callable[..., list[tuple[float, float, float]]]  # (area, skip=...) -> discs

TRAY_HALF = (0.13, 0.17, 0.045)  # half depth (u), half width (v), rim height
TRAY_U = 0.88  # where it stands on a table, in its area's frame
TRAY_SPOTS = ((-0.06, 0.06), (-0.06, -0.06), (0.06, 0.06), (0.06, -0.06))


@dataclass
class Hold:
    """The tray in both hands: it follows the left hand with this offset."""

    tray: str
    constraint: int
    rel: tuple
    riders: tuple = ()  # what stood on the tray when it was lifted


def make_tray(physics: Physics, frames: AreaFrames, name: str, area: str) -> int:
    """The tray ``name`` on ``area``'s table; its body."""
    top = physics.furniture_top[area]
    yaw = frames.frame(area)[2]
    hu, hv, hz = TRAY_HALF
    x, y = frames.to_world(area, TRAY_U, 0.0)
    bid = physics.boxes(
        open_box(hu, hv, hz / 2, wall=0.008), 0.6, [x, y, top + 0.002], yaw, (0.3, 0.3, 0.3, 1)
    )
    physics.p.changeDynamics(bid, -1, lateralFriction=1.0, physicsClientId=physics.cid)
    physics.body_of[name] = bid
    return bid


def tray_discs(u: float, v: float) -> list[tuple[float, float, float]]:
    """Four discs (u, v, radius) covering a tray centred at (u, v) of an area."""
    return [(u + du, v + dv, 0.12) for du in (-0.07, 0.07) for dv in (-0.09, 0.09)]


class Trays:
    """The kitchen robot's part for trays: ``bodies`` by name, and the one
    in both hands (``hold``). ``footprints`` says what occupies a table
    (:meth:`~htn.robot.table_spots.TableSpots.footprints`), where a tray is lowered."""

    def __init__(
        self,
        physics: Physics,
        frames: AreaFrames,
        world: World,
        base: MobileBase,
        arms: TwoArms,
        footprints: Footprints,
        bodies: dict[str, int],
    ):
        self.physics, self.frames, self.world = physics, frames, world
        self.base, self.arms, self.footprints = base, arms, footprints
        self.bodies = bodies
        self.hold: Hold | None = None

    def on_tray(self, tray: str) -> list[str]:
        ph = self.physics
        bid = self.bodies[tray]
        tp = ph.pos(bid)
        out = []
        for t in self.world.things:
            if t in self.arms.hands.values():
                continue
            pos = ph.body_pos(t)
            if (
                ph.touching(ph.body_of[t], bid)
                and pos[2] > tp[2]
                and math.hypot(*(pos[:2] - tp[:2])) < 0.25
            ):
                out.append(t)
        return out

    def follow(self) -> None:
        """Keep the carried tray where the left hand holds it (every physics step)."""
        if self.hold is None:
            return
        p, c = self.physics.p, self.physics.cid
        ee_pos, ee_orn = p.getLinkState(self.arms.left.body, EE_LINK, physicsClientId=c)[4:6]
        pos, orn = p.multiplyTransforms(ee_pos, ee_orn, *self.hold.rel)
        p.changeConstraint(
            self.hold.constraint,
            jointChildPivot=pos,
            jointChildFrameOrientation=orn,
            maxForce=300,
            physicsClientId=c,
        )

    def free_spot(self, tray: str, arm: str) -> tuple[float, float, float] | None:
        """A free spot on ``tray`` that ``arm`` reaches: world x, y and the tray's floor."""
        p, c = self.physics.p, self.physics.cid
        tpos, torn = p.getBasePositionAndOrientation(self.bodies[tray], physicsClientId=c)
        on = [self.physics.body_pos(t) for t in self.on_tray(tray)]
        for du, dv in sorted(TRAY_SPOTS, key=lambda s: -s[1] * SIDE[arm]):
            x, y = p.multiplyTransforms(tpos, torn, [du, dv, 0], [0, 0, 0, 1])[0][:2]
            if all(math.hypot(x - o[0], y - o[1]) > 0.07 for o in on) and self.arms[arm].reachable(
                [x, y, tpos[2] + 0.2]
            ):
                return x, y, tpos[2] + 0.008
        return None

    def _rims(self, pos, orn) -> dict:
        """Where each hand holds the tray (posed at pos, orn): the middle of its side rim."""
        hv = TRAY_HALF[1] - 0.004
        z = TRAY_HALF[2] - 0.01
        return {
            a: list(
                self.physics.p.multiplyTransforms(pos, orn, [0, SIDE[a] * hv, z], [0, 0, 0, 1])[0]
            )
            for a in self.arms.NAMES
        }

    # ------------------------------------------------------------ skills
    def lift(self, tray: str):
        if tray not in self.bodies:
            return SkillResult(False, f"no tray {tray}")
        if any(self.arms.hands.values()) or self.hold is not None:
            return SkillResult(False, "the tray needs both hands free")
        arms, ph = self.arms, self.physics
        p, c = ph.p, ph.cid
        bid = self.bodies[tray]
        pos, orn = p.getBasePositionAndOrientation(bid, physicsClientId=c)
        rims = self._rims(pos, orn)
        above = {a: [r[0], r[1], r[2] + 0.1] for a, r in rims.items()}
        lifted = {a: [r[0], r[1], r[2] + 0.12] for a, r in rims.items()}
        for arm in arms.all():
            arm.set_fingers(0.04)
        for stage in (above, rims):
            qs = {a: arms[a].ik(stage[a]) for a in arms.NAMES}
            if any(q is None for q in qs.values()):
                yield from arms.home_both()
                return SkillResult(False, f"{tray} is out of reach of both arms")
            yield from arms.move_both(qs, 0.8)
        self._hands_touch_tray(bid, False)  # they hold its rims: no contact forces
        for arm in arms.all():
            arm.set_fingers(0.004)
        yield from ph.step(6)
        ee_pos, ee_orn = p.getLinkState(arms.left.body, EE_LINK, physicsClientId=c)[4:6]
        inv = p.invertTransform(ee_pos, ee_orn)
        rel = p.multiplyTransforms(inv[0], inv[1], pos, orn)
        cid = p.createConstraint(
            bid,
            -1,
            -1,
            -1,
            p.JOINT_FIXED,
            [0, 0, 0],
            [0, 0, 0],
            pos,
            childFrameOrientation=orn,
            physicsClientId=c,
        )
        self.hold = Hold(tray, cid, rel, tuple(self.on_tray(tray)))
        goals = {a: arms[a].ik(lifted[a]) for a in arms.NAMES}
        if any(q is None for q in goals.values()):
            yield from self._let_go()
            return SkillResult(False, f"the arms cannot lift {tray}")
        yield from arms.move_both(goals, 1.0)
        yield from ph.step(24)
        return SkillResult(True, f"{tray} lifted with both hands")

    def lower(self, tray: str, where: str):
        if self.hold is None or self.hold.tray != tray:
            return SkillResult(True, f"{tray} is not in the hands")
        if where not in self.physics.furniture_top:
            return SkillResult(False, f"no table at {where}")
        p = self.physics.p
        top = self.physics.furniture_top[where]
        yaw = self.base.pose[2]
        taken = self.footprints(where, skip=self.on_tray(tray))
        for v in (0.0, -0.1, 0.1, -0.2, 0.2, -0.3, 0.3):
            if any(
                math.hypot(u - tu, w - tv) < tr + 0.1
                for u, w, _ in tray_discs(TRAY_U, v)
                for tu, tv, tr in taken
            ):
                continue
            x, y = self.frames.to_world(where, TRAY_U, v)
            pos, orn = [x, y, top + 0.004], yaw_quat(p, yaw)
            rims = self._rims(pos, orn)
            ee_goal = p.multiplyTransforms(pos, orn, *p.invertTransform(*self.hold.rel))[0]
            left = self.arms.left.ik(ee_goal)
            right = self.arms.right.ik([*rims["right"][:2], ee_goal[2]])
            if left is not None and right is not None:
                break
        else:
            return SkillResult(False, f"no free place for {tray} within reach on {where}")
        yield from self.arms.move_both({"left": left, "right": right}, 1.2)
        yield from self._let_go()
        yield from self.arms.home_both()
        return SkillResult(True, f"{tray} lowered onto {where}")

    def _hands_touch_tray(self, tray_body: int, touch: bool) -> None:
        p, c = self.physics.p, self.physics.cid
        for arm in self.arms.all():
            for link in (*FINGERS, 8, 7, 6):
                p.setCollisionFilterPair(
                    arm.body, tray_body, link, -1, int(touch), physicsClientId=c
                )

    def _let_go(self):
        """Release the tray where it is: let it settle, open and raise both hands."""
        bid = self.bodies[self.hold.tray]
        self.physics.p.removeConstraint(self.hold.constraint, physicsClientId=self.physics.cid)
        self.hold = None
        yield from self.physics.settle(0.3)
        arms = self.arms
        for arm in arms.all():
            arm.set_fingers(0.04)
        ups = {a: arms[a].ik([*arms[a].ee()[:2], arms[a].ee()[2] + 0.1]) for a in arms.NAMES}
        yield from arms.move_both({a: q for a, q in ups.items() if q is not None}, 0.4)
        self._hands_touch_tray(bid, True)

    # ------------------------------------------------------------ checks
    def check_on_tray(self, obj: str, tray: str) -> Check:
        if tray not in self.bodies or obj not in self.physics.body_of:
            return Check(False, f"unknown tray or object {tray}/{obj}")
        ok = obj in self.on_tray(tray)
        return Check(ok, f"{obj} {'rests' if ok else 'does not rest'} on {tray}")

    def check_carried(self, tray: str, carried: bool, where: str | None = None) -> Check:
        if tray not in self.bodies:
            return Check(False, f"no tray {tray}")
        bid = self.bodies[tray]
        z = self.physics.pos(bid)[2]
        if carried:
            top = max(self.physics.furniture_top.values(), default=0.0)
            ok = self.hold is not None and self.hold.tray == tray and z > top + 0.06
            return Check(ok, f"{tray} held {z - top:.2f} m above the table tops")
        ok = self.hold is None and where is not None and self.physics.on_top(bid, where)
        return Check(
            ok, f"{tray} rests on " + (f"the table of {where}" if ok else "something else")
        )
