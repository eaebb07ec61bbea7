"""A container of the kitchen: a drawer that slides out of a housing standing
on its area's table.

Closed, its contents can be neither seen nor reached (the housing covers
them). A free hand pulls it by the top of its front wall; the drawer, and what
lies in it, follows the hand along its rail. The bodies are made while the
world is built (:func:`make_drawer`), before the arms that pull them exist;
the :class:`Drawers` part acts on them afterwards.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

from .areas import AreaFrames
from .interface import Check, SkillResult
from .physics import DT, Physics, open_box
from .two_arms import SideArm, TwoArms
from .world import World

DRAWER_U, DRAWER_V = 0.95, 0.3  # the closed drawer's centre, in its area's frame
DRAWER_HALF = (0.12, 0.12, 0.025)  # the drawer box: half depth, width, half wall height
HOUSING_HEIGHT = 0.11
DRAWER_OPEN = 0.23  # how far it slides out
PULL_SPEED = 0.2  # m/s


@dataclass
class Drawer:
    name: str
    area: str
    body: int
    out: float = 0.0  # how far it is pulled out (m)


def make_drawer(physics: Physics, frames: AreaFrames, name: str, area: str, opened: bool) -> Drawer:
    """The housing and the drawer on ``area``'s table, the drawer pulled out if ``opened``."""
    top = physics.furniture_top[area]
    yaw = frames.frame(area)[2]
    hu, hv, hz = DRAWER_HALF
    x, y = frames.to_world(area, DRAWER_U, DRAWER_V)
    # the housing: top, sides and back, open towards the robot
    t = 0.01
    H = HOUSING_HEIGHT / 2
    housing = physics.boxes(
        [
            ((hu + t, hv + 2 * t, t / 2), (0, 0, 2 * H - t / 2)),
            ((hu + t, t / 2, H), (0, hv + 1.5 * t, H)),
            ((hu + t, t / 2, H), (0, -hv - 1.5 * t, H)),
            ((t / 2, hv + 2 * t, H), (hu + 1.5 * t, 0, H)),
        ],
        0.0,
        [x, y, top],
        yaw,
        (0.55, 0.4, 0.25, 1),
    )
    body = physics.boxes(open_box(hu, hv, hz), 0.0, [x, y, top + 0.001], yaw, (0.75, 0.6, 0.4, 1))
    d = Drawer(name, area, body)
    physics.body_of[name] = body
    physics.body_of[f"{name}-housing"] = housing
    if opened:
        slide(physics, frames, d, DRAWER_OPEN, [])
    return d


def slide(physics: Physics, frames: AreaFrames, d: Drawer, out: float, contents: list) -> None:
    """Move the drawer (and the bodies ``contents``) to ``out`` metres pulled out."""
    p, c = physics.p, physics.cid
    _, _, yaw = frames.frame(d.area)
    du = -(out - d.out)
    dx, dy = du * math.cos(yaw), du * math.sin(yaw)
    for body in [d.body] + contents:
        pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=c)
        p.resetBasePositionAndOrientation(
            body, [pos[0] + dx, pos[1] + dy, pos[2]], orn, physicsClientId=c
        )
        if body != d.body:
            p.resetBaseVelocity(body, [0, 0, 0], [0, 0, 0], physicsClientId=c)
    d.out = out


def in_drawer_spot(
    physics: Physics, frames: AreaFrames, d: Drawer, slot: int
) -> tuple[float, float, float]:
    """Where the ``slot``-th object lies in the drawer (world x, y, its bottom)."""
    u = DRAWER_U - d.out + (0.05 if slot % 4 >= 2 else -0.05)
    v = DRAWER_V + (0.05 if slot % 2 else -0.05)
    x, y = frames.to_world(d.area, u, v)
    return x, y, physics.furniture_top[d.area] + 0.007


def drawer_discs(drawers: Mapping[str, Drawer], area: str) -> list[tuple[float, float, float]]:
    """Discs (u, v, radius) the housings and the drawers pulled out cover on the table."""
    return [
        (u, DRAWER_V, 0.17)
        for d in drawers.values()
        if d.area == area
        for u in (DRAWER_U, DRAWER_U - DRAWER_OPEN)
    ]


class Drawers(Mapping):
    """The kitchen robot's part for drawers (by name): pulling, what is in
    one, checking."""

    def __init__(
        self,
        physics: Physics,
        frames: AreaFrames,
        world: World,
        arms: TwoArms,
        drawers: dict[str, Drawer],
    ):
        self.physics, self.frames, self.world, self.arms = physics, frames, world, arms
        self._drawers = drawers

    def __getitem__(self, name: str) -> Drawer:
        return self._drawers[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._drawers)

    def __len__(self) -> int:
        return len(self._drawers)

    def pull(self, container: str, opened: bool):
        """The skill: open (``opened``) or close ``container`` with a free hand."""
        d = self._drawers.get(container)
        if d is None:
            return SkillResult(False, f"no drawer {container}")
        goal, verb = (DRAWER_OPEN, "opened") if opened else (0.0, "closed")
        return (yield from self._pull(d, goal, verb))

    def _pull(self, d: Drawer, goal: float, verb: str):
        name = self.arms.pick(None)
        if name is None:
            return SkillResult(False, f"both hands are full: {d.name} stays as it is")
        arm: SideArm = self.arms[name]
        ph, frames = self.physics, self.frames
        top = ph.furniture_top[d.area]
        grip_z = top + 2 * DRAWER_HALF[2] - 0.01

        def handle(out):  # the top of the drawer's front wall
            return [
                *frames.to_world(d.area, DRAWER_U - out - DRAWER_HALF[0] + 0.003, DRAWER_V),
                grip_z,
            ]

        contents = [
            ph.body_of[t] for t in self.world.things if t in ph.body_of and self.holds(t, d)
        ]
        arm.set_fingers(0.04)
        start = handle(d.out)
        if not (yield from arm.reach([start[0], start[1], grip_z + 0.1], 0.8)) or not (
            yield from arm.reach(start, 0.5)
        ):
            yield from arm.rest()
            return SkillResult(False, f"the handle of {d.name} is out of the {name} arm's reach")
        arm.set_fingers(0.002)
        yield from ph.step(6)
        q0 = arm.q()
        q1 = arm.ik(handle(goal))
        if q1 is None:
            yield from arm.rest()
            return SkillResult(False, f"the {name} arm cannot reach where {d.name} is {verb}")
        n = max(1, int(abs(goal - d.out) / (PULL_SPEED * DT)))
        for i in range(1, n + 1):
            k = i / n
            arm.command([a + (b - a) * k for a, b in zip(q0, q1)])
            # the drawer follows the hand along its rail
            ee_u, _ = frames.to_area(d.area, *arm.ee()[:2])
            out = min(DRAWER_OPEN, max(0.0, DRAWER_U - DRAWER_HALF[0] + 0.003 - ee_u))
            slide(ph, frames, d, out, contents)
            yield from ph.step()
        arm.set_fingers(0.04)
        end = arm.ee()
        yield from arm.reach([end[0], end[1], grip_z + 0.1], 0.4)
        yield from arm.rest()
        return SkillResult(True, f"{d.name} {verb} by the {name} arm ({d.out:.2f} m out)")

    def holds(self, obj: str, d: Drawer) -> bool:
        """Does ``obj`` lie in drawer ``d`` (not in a hand above it)?"""
        pos = self.physics.body_pos(obj)
        dp = self.physics.pos(d.body)
        u, v = self.frames.to_area(d.area, pos[0], pos[1])
        du, dv = self.frames.to_area(d.area, dp[0], dp[1])
        return (
            abs(u - du) < DRAWER_HALF[0]
            and abs(v - dv) < DRAWER_HALF[1]
            and dp[2] <= pos[2] < dp[2] + 2 * DRAWER_HALF[2] + 0.05
            and obj not in self.arms.hands.values()
        )

    def container_of(self, obj: str) -> Drawer | None:
        return next((d for d in self._drawers.values() if self.holds(obj, d)), None)

    @staticmethod
    def is_open(d: Drawer) -> bool:
        return d.out >= 0.8 * DRAWER_OPEN

    def check_opened(self, container: str, opened: bool) -> Check:
        d = self._drawers.get(container)
        if d is None:
            return Check(False, f"no drawer {container}")
        ok = self.is_open(d) if opened else d.out <= 0.02
        return Check(ok, f"{container} is {d.out:.2f} m out")
