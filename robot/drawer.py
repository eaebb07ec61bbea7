"""A container of the kitchen: a drawer that slides out of a housing standing
on its area's table.

Closed, its contents can be neither seen nor reached (the housing covers
them). A free hand pulls it by the top of its front wall; the drawer, and what
lies in it, follows the hand along its rail.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

from .interface import Check, SkillResult, check, skill
from .physics import DT

DRAWER_U, DRAWER_V = 0.95, 0.3      # the closed drawer's centre, in its area's frame
DRAWER_HALF = (0.12, 0.12, 0.025)   # the drawer box: half depth, width, half wall height
HOUSING_HEIGHT = 0.11
DRAWER_OPEN = 0.23                  # how far it slides out
PULL_SPEED = 0.2                    # m/s


@dataclass
class Drawer:
    name: str
    area: str
    body: int
    out: float = 0.0                # how far it is pulled out (m)


class Drawers:
    """The kitchen robot's part for drawers: building, pulling, checking."""

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

    def _in_drawer_spot(self, d: Drawer, slot: int) -> tuple[float, float, float]:
        u = DRAWER_U - d.out + (0.05 if slot % 4 >= 2 else -0.05)
        v = DRAWER_V + (0.05 if slot % 2 else -0.05)
        x, y = self._to_world(d.area, u, v)
        return x, y, self.furniture_top[d.area] + 0.007

    def _drawer_discs(self, area: str) -> list[tuple[float, float, float]]:
        """Discs (u, v, radius) the housing and the drawer pulled out cover on the table."""
        return [(u, DRAWER_V, 0.17) for d in self.drawers.values() if d.area == area
                for u in (DRAWER_U, DRAWER_U - DRAWER_OPEN)]

    def _slide_drawer(self, d: Drawer, out: float, contents: list) -> None:
        """Move the drawer (and what lies in it) to ``out`` metres pulled out."""
        p, c = self.p, self.cid
        _, _, yaw = self._frame(d.area)
        du = -(out - d.out)
        dx, dy = du * math.cos(yaw), du * math.sin(yaw)
        for body in [d.body] + contents:
            pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=c)
            p.resetBasePositionAndOrientation(body, [pos[0] + dx, pos[1] + dy, pos[2]], orn,
                                              physicsClientId=c)
            if body != d.body:
                p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=c)
        d.out = out

    def _pull(self, d: Drawer, goal: float, verb: str):
        arm = self._pick_arm(None)
        if arm is None:
            return SkillResult(False, f"both hands are full: {d.name} stays as it is")
        top = self.furniture_top[d.area]
        grip_z = top + 2 * DRAWER_HALF[2] - 0.01

        def handle(out):   # the top of the drawer's front wall
            return [*self._to_world(d.area, DRAWER_U - out - DRAWER_HALF[0] + 0.003, DRAWER_V),
                    grip_z]
        contents = [self.body_of[t] for t in self.world.things
                    if t in self.body_of and self._in_drawer(t, d)]
        with self._using(arm):
            self._set_fingers(0.04)
            start = handle(d.out)
            if not (yield from self._reach([start[0], start[1], grip_z + 0.1], 0.8)) or \
                    not (yield from self._reach(start, 0.5)):
                yield from self._rest_pose()
                return SkillResult(False, f"the handle of {d.name} is out of the {arm} arm's reach")
            self._set_fingers(0.002)
            yield from self._step(6)
            q0 = self._arm_q()
            q1 = self._ik(handle(goal))
            if q1 is None:
                yield from self._rest_pose()
                return SkillResult(False, f"the {arm} arm cannot reach where {d.name} is {verb}")
            n = max(1, int(abs(goal - d.out) / (PULL_SPEED * DT)))
            for i in range(1, n + 1):
                k = i / n
                self._command(arm, [a + (b - a) * k for a, b in zip(q0, q1)])
                # the drawer follows the hand along its rail
                ee_u, _ = self._to_area(d.area, *self._ee()[:2])
                out = min(DRAWER_OPEN, max(0.0, DRAWER_U - DRAWER_HALF[0] + 0.003 - ee_u))
                self._slide_drawer(d, out, contents)
                yield from self._step()
            self._set_fingers(0.04)
            end = self._ee()
            yield from self._reach([end[0], end[1], grip_z + 0.1], 0.4)
            yield from self._rest_pose()
        return SkillResult(True, f"{d.name} {verb} by the {arm} arm ({d.out:.2f} m out)")

    @skill("open_container")
    def open_container(self, container: str):
        d = self.drawers.get(container)
        if d is None:
            return SkillResult(False, f"no drawer {container}")
        return (yield from self._pull(d, DRAWER_OPEN, "opened"))

    @skill("close_container")
    def close_container(self, container: str):
        d = self.drawers.get(container)
        if d is None:
            return SkillResult(False, f"no drawer {container}")
        return (yield from self._pull(d, 0.0, "closed"))

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

    def _is_open(self, d: Drawer) -> bool:
        return d.out >= 0.8 * DRAWER_OPEN

    @check("opened")
    def check_opened(self, container: str, opened: bool) -> Check:
        d = self.drawers.get(container)
        if d is None:
            return Check(False, f"no drawer {container}")
        ok = self._is_open(d) if opened else d.out <= 0.02
        return Check(ok, f"{container} is {d.out:.2f} m out")
