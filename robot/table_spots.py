"""Where things stand on an area's table (the kitchen robot): what occupies
the table, and a free spot within an arm's reach. Geometry is in the area's
frame (:mod:`~htn.robot.areas`)."""

from __future__ import annotations

import math
from collections.abc import Mapping

from .areas import AreaFrames
from .drawer import Drawer, drawer_discs
from .physics import Physics
from .tray import tray_discs
from .two_arms import Hands, SideArm
from .world import World

ROWS = (0.70, 0.84)  # u of the spots where objects stand on a table
SPOT_VS = tuple(round(-0.55 + 0.1 * i, 2) for i in range(12))


class TableSpots:
    """Places on the tables of the kitchen's areas. Made while the world is
    built (objects are placed with it), so it is handed the drawers and the
    trays' bodies, the objects' radii and what the hands hold, not the arms."""

    def __init__(
        self,
        physics: Physics,
        frames: AreaFrames,
        world: World,
        drawers: Mapping[str, Drawer],
        trays: Mapping[str, int],
        radius: Mapping[str, float],
        hands: Hands,
    ):
        self.physics, self.frames, self.world = physics, frames, world
        self.drawers, self.trays, self.radius, self.hands = drawers, trays, radius, hands

    def footprints(self, area: str, skip=()) -> list[tuple[float, float, float]]:
        """Discs (u, v, radius) of what occupies the area's table."""
        ph, frames = self.physics, self.frames
        out = drawer_discs(self.drawers, area)
        for bid in self.trays.values():
            pos = ph.pos(bid)
            if ph.on_top(bid, area):
                out += tray_discs(*frames.to_area(area, pos[0], pos[1]))
        for t in self.world.things:
            if t in ph.body_of and t not in skip and t not in self.hands.values():
                pos = ph.body_pos(t)
                u, v = frames.to_area(area, pos[0], pos[1])
                if 0.4 < u < 1.7 and abs(v) < 0.9:
                    out.append((u, v, self.radius[t]))
        return out

    def free_spot(
        self, area: str, arm: SideArm | None, radius: float, skip=()
    ) -> tuple[float, float, float] | None:
        """A free spot on the area's table: near the front, on the side of
        ``arm`` and within its reach (any, without an arm). Returns world
        (x, y, table top) or None."""
        taken = self.footprints(area, skip)
        side = arm.side if arm is not None else 0.0
        spots = sorted(
            ((u, v) for u in ROWS for v in SPOT_VS),
            key=lambda s: abs(s[1] - 0.15 * side) + 0.8 * (s[0] - ROWS[0]),
        )
        top = self.physics.furniture_top[area]
        for u, v in spots:
            if all(math.hypot(u - tu, v - tv) > radius + tr + 0.04 for tu, tv, tr in taken):
                x, y = self.frames.to_world(area, u, v)
                if arm is None or arm.reachable([x, y, top + 0.2]):
                    return x, y, top
        return None
