"""Where things stand on an area's table (the kitchen robot): each area's
frame (``u`` forward from the base pose towards the table, ``v`` to the
robot's left), what occupies its table, and a free spot within an arm's reach."""
from __future__ import annotations

import math
from typing import Optional

from .tray import SIDE

ROWS = (0.70, 0.84)                 # u of the spots where objects stand on a table
SPOT_VS = tuple(round(-0.55 + 0.1 * i, 2) for i in range(12))


class TableSpots:
    """Places on the tables of the kitchen's areas."""

    def _frame(self, area: str) -> tuple[float, float, float]:
        pl = self.world.places[area]
        return pl.x, pl.y, pl.theta

    def _to_world(self, area: str, u: float, v: float) -> tuple[float, float]:
        x, y, yaw = self._frame(area)
        return (x + u * math.cos(yaw) - v * math.sin(yaw),
                y + u * math.sin(yaw) + v * math.cos(yaw))

    def _to_area(self, area: str, x: float, y: float) -> tuple[float, float]:
        ax, ay, yaw = self._frame(area)
        dx, dy = x - ax, y - ay
        return (dx * math.cos(yaw) + dy * math.sin(yaw), -dx * math.sin(yaw) + dy * math.cos(yaw))

    def _footprints(self, area: str, skip=()) -> list[tuple[float, float, float]]:
        """Discs (u, v, radius) of what occupies the area's table."""
        out = self._drawer_discs(area)
        for bid in self.trays.values():
            pos = self._pos(bid)
            if self._on_table(bid, area):
                out += self._tray_discs(*self._to_area(area, pos[0], pos[1]))
        for t in self.world.things:
            if t in self.body_of and t not in skip and t not in self.arm_held.values():
                pos = self._body_pos(t)
                u, v = self._to_area(area, pos[0], pos[1])
                if 0.4 < u < 1.7 and abs(v) < 0.9:
                    out.append((u, v, self.radius[t]))
        return out

    def _free_spot(self, area: str, arm: Optional[str], radius: float, skip=()):
        """A free, reachable spot on the area's table: near the front, on the
        arm's side. Returns world (x, y, table top) or None."""
        taken = self._footprints(area, skip)
        side = SIDE.get(arm, 0.0)
        spots = sorted(((u, v) for u in ROWS for v in SPOT_VS),
                       key=lambda s: (abs(s[1] - 0.15 * side) + 0.8 * (s[0] - ROWS[0])))
        top = self.furniture_top[area]
        for u, v in spots:
            if all(math.hypot(u - tu, v - tv) > radius + tr + 0.04 for tu, tv, tr in taken):
                x, y = self._to_world(area, u, v)
                if arm is None or self._reachable(arm, [x, y, top + 0.2]):
                    return x, y, top
        return None
