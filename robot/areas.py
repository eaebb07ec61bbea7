"""The frame of each kitchen area (the kitchen robot): ``u`` forward from
the area's base pose towards its table, ``v`` to the robot's left. The
drawers, the trays and the spots on a table are placed in it."""

from __future__ import annotations

import math

from .world import World


class AreaFrames:
    """Conversions between an area's frame and the world's."""

    def __init__(self, world: World):
        self.world = world

    def frame(self, area: str) -> tuple[float, float, float]:
        pl = self.world.places[area]
        return pl.x, pl.y, pl.theta

    def to_world(self, area: str, u: float, v: float) -> tuple[float, float]:
        x, y, yaw = self.frame(area)
        return (
            x + u * math.cos(yaw) - v * math.sin(yaw),
            y + u * math.sin(yaw) + v * math.cos(yaw),
        )

    def to_area(self, area: str, x: float, y: float) -> tuple[float, float]:
        ax, ay, yaw = self.frame(area)
        dx, dy = x - ax, y - ay
        return (dx * math.cos(yaw) + dy * math.sin(yaw), -dx * math.sin(yaw) + dy * math.cos(yaw))
