"""The world a problem describes: places, furniture, objects, persons, robots.

Built from a problem's initial state, so one file drives both planning and
simulation. The vocabulary is the domestic domain's (see its header):
``(location l x y theta_degrees)``, ``(furniture f kind x y approach_location)``,
``(object o kind)``, ``(object_on o f)``, ``(graspable o top|side)``,
``(person p x y)``, ``(person_at p l)``, ``(can_receive p)``, ``(robot r)``,
``(robot_at r l)``, ``(free_hand r)``, ``(holding r o)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from htn.jshop.language.errors import HtnError

if TYPE_CHECKING:
    from htn.jshop.language.syntax import Pos


@dataclass
class Place:
    name: str
    x: float
    y: float
    theta: float  # radians

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.x, self.y, self.theta


@dataclass
class Furniture:
    name: str
    kind: str
    x: float
    y: float
    approach: str  # name of the Place the robot works from


@dataclass
class Thing:
    name: str
    kind: str
    on: str | None = None  # furniture name
    grasps: tuple = ()


@dataclass
class Person:
    name: str
    x: float
    y: float
    at: str | None = None  # Place where the robot meets them
    can_receive: bool = False


@dataclass
class World:
    places: dict = field(default_factory=dict)
    furniture: dict = field(default_factory=dict)
    things: dict = field(default_factory=dict)
    persons: dict = field(default_factory=dict)
    robot: str = "robot"
    robot_at: str | None = None
    holding: str | None = None
    static_facts: list = field(default_factory=list)  # (pred, args) never changed by actions
    # the kitchen (pick and place) vocabulary, see kitchen_world_from_state
    containers: dict = field(default_factory=dict)  # container -> area
    trays: dict = field(default_factory=dict)  # tray -> area
    opened: set = field(default_factory=set)  # containers open at the start

    def place(self, name: str) -> Place:
        try:
            return self.places[name]
        except KeyError:
            raise HtnError(
                f"unknown location '{name}' (no (location {name} x y theta) fact)"
            ) from None


def number_arg(args, i, what, pos) -> float:
    """Argument ``i`` of a ``(what ...)`` atom of the state, which must be a
    number; else an error at the atom (an IndexError if there is none)."""
    v = args[i]
    if type(v) is not float:
        raise HtnError.at(pos, f"{what}: expected a number, got {v}")
    return v


def world_from_state(atoms) -> World:
    """Read a :class:`World` from the atoms of a problem's initial state."""
    w = World()
    for a in atoms:
        p, args, pos = a.pred, a.args, a.pos
        try:
            if p == "location":
                w.places[args[0]] = Place(
                    args[0],
                    number_arg(args, 1, p, pos),
                    number_arg(args, 2, p, pos),
                    math.radians(number_arg(args, 3, p, pos)),
                )
            elif p == "furniture":
                w.furniture[args[0]] = Furniture(
                    args[0],
                    args[1],
                    number_arg(args, 2, p, pos),
                    number_arg(args, 3, p, pos),
                    args[4],
                )
            elif p == "object":
                w.things.setdefault(args[0], Thing(args[0], args[1])).kind = args[1]
            elif p == "object_on":
                w.things.setdefault(args[0], Thing(args[0], "object")).on = args[1]
            elif p == "graspable":
                t = w.things.setdefault(args[0], Thing(args[0], "object"))
                t.grasps = t.grasps + (args[1],)
            elif p == "person":
                w.persons.setdefault(args[0], Person(args[0], 0.0, 0.0))
                w.persons[args[0]].x = number_arg(args, 1, p, pos)
                w.persons[args[0]].y = number_arg(args, 2, p, pos)
            elif p == "person_at":
                w.persons.setdefault(args[0], Person(args[0], 0.0, 0.0)).at = args[1]
            elif p == "can_receive":
                w.persons.setdefault(args[0], Person(args[0], 0.0, 0.0)).can_receive = True
            elif p == "robot":
                w.robot = args[0]
            elif p == "robot_at":
                w.robot_at = args[1]
            elif p == "holding":
                w.holding = args[1]
        except IndexError:
            raise HtnError.at(pos, f"({p} ...) has too few arguments") from None
    if w.robot_at is None:
        raise HtnError("the initial state has no (robot_at ROBOT LOCATION) fact")
    w.place(w.robot_at)
    for f in w.furniture.values():
        w.place(f.approach)
    return w


# ---------------------------------------------------------------- the kitchen

TABLE_GAP = 0.58  # from an area's base pose to the near edge of its table
TABLE_DEPTH, TABLE_WIDTH = 1.0, 1.5
ROBOT_HALF_WIDTH = 0.45  # half the width of the corridor the base (arms tucked) sweeps


def is_kitchen_state(atoms) -> bool:
    """Does the state use the kitchen domain's vocabulary (``(area a x y)`` facts)?"""
    return any(a.pred == "area" for a in atoms)


def kitchen_world_from_state(atoms) -> World:
    """Read a kitchen problem's initial state into a :class:`World`.

    The kitchen domain only names working areas and the base pose there
    (``(area a x y)``); the simulation needs furniture. Each area gets a table
    in front of its base pose, turned so that no straight drive between two
    areas (the base's corridor) and no other table comes near it. The heading
    of the area's base pose is the direction it faces its table. A layout that
    cannot be built (areas too close together) is an error.
    """
    w = World()
    areas: dict[str, tuple] = {}
    said: dict[tuple, Pos | None] = {}  # (predicate, first argument) -> position in the file
    start_pos = None
    for a in atoms:
        p, args, pos = a.pred, a.args, a.pos
        if args:
            said[(p, args[0])] = pos
        try:
            if p == "area":
                areas[args[0]] = (number_arg(args, 1, p, pos), number_arg(args, 2, p, pos))
            elif p in ("at", "in"):  # on an area's table, in a container
                w.things.setdefault(args[0], Thing(args[0], _kind(args[0]))).on = args[1]
            elif p == "container":
                w.containers[args[0]] = args[1]
            elif p == "tray":
                w.trays[args[0]] = args[1]
            elif p == "opened":
                w.opened.add(args[0])
            elif p == "robot-at":
                w.robot_at, start_pos = args[0], pos
            elif p == "holding":
                raise HtnError.at(
                    pos,
                    "the simulated kitchen starts with empty hands "
                    f"(the state says (holding {' '.join(map(str, args))}))",
                )
        except IndexError:
            raise HtnError.at(pos, f"({p} ...) has too few arguments") from None
    if w.robot_at is None:
        raise HtnError("the initial state has no (robot-at AREA) fact")
    if w.robot_at not in areas:
        raise HtnError.at(
            start_pos, f"the robot is at '{w.robot_at}', which has no (area {w.robot_at} x y) fact"
        )
    for kind, table in (("container", w.containers), ("tray", w.trays)):
        for name, where in table.items():
            if where not in areas:
                raise HtnError.at(
                    said.get((kind, name)),
                    f"{name} is at '{where}', which has no (area {where} x y) fact",
                )
    for t in w.things.values():
        if t.on not in areas and t.on not in w.containers:
            raise HtnError.at(
                said.get(("at", t.name), said.get(("in", t.name))),
                f"{t.name} is at '{t.on}', which is neither an area nor a container",
            )
    # every area gets a table, but the robot's start is just a pose unless
    # something stands there
    used = {t.on for t in w.things.values()} | set(w.containers.values()) | set(w.trays.values())
    tables = _layout_tables(
        areas,
        [a for a in areas if a != w.robot_at or a in used],
        {a: said.get(("area", a)) for a in areas},
    )
    for name, (x, y) in areas.items():
        yaw = tables[name][2] if name in tables else 0.0
        w.places[name] = Place(name, x, y, yaw)
    for name, (cx, cy, _yaw) in tables.items():
        w.furniture[name] = Furniture(name, "table", cx, cy, name)
    return w


def _kind(name: str) -> str:
    """An object's kind from its name: bowl1 -> bowl."""
    return name.rstrip("0123456789_") or name


def _table_rect(x: float, y: float, yaw: float) -> list:
    """Corners of the table in front of base pose (x, y, yaw)."""
    ux, uy = math.cos(yaw), math.sin(yaw)
    vx, vy = -uy, ux
    near, far, half = TABLE_GAP, TABLE_GAP + TABLE_DEPTH, TABLE_WIDTH / 2
    return [
        (x + ux * u + vx * v, y + uy * u + vy * v)
        for u, v in ((near, -half), (far, -half), (far, half), (near, half))
    ]


def _seg_dist(a, b, c, d) -> float:
    """Distance between segments ab and cd (0 if they cross)."""

    def cross(o, p, q):
        return (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])

    def pt_seg(p, s, t):
        sx, sy = t[0] - s[0], t[1] - s[1]
        n = sx * sx + sy * sy
        k = 0.0 if n == 0 else max(0.0, min(1.0, ((p[0] - s[0]) * sx + (p[1] - s[1]) * sy) / n))
        return math.hypot(p[0] - s[0] - k * sx, p[1] - s[1] - k * sy)

    if cross(a, b, c) * cross(a, b, d) < 0 and cross(c, d, a) * cross(c, d, b) < 0:
        return 0.0
    return min(pt_seg(a, c, d), pt_seg(b, c, d), pt_seg(c, a, b), pt_seg(d, a, b))


def _inside(p, rect) -> bool:
    signs = [
        (q[0] - o[0]) * (p[1] - o[1]) - (q[1] - o[1]) * (p[0] - o[0])
        for o, q in zip(rect, rect[1:] + rect[:1])
    ]
    return all(s >= 0 for s in signs) or all(s <= 0 for s in signs)


def _rect_seg_dist(rect, a, b) -> float:
    if _inside(a, rect) or _inside(b, rect):
        return 0.0
    return min(_seg_dist(a, b, c, d) for c, d in zip(rect, rect[1:] + rect[:1]))


def _layout_tables(areas: dict, with_table: list, where_said: dict) -> dict:
    """Headings for the areas' tables: each table keeps clear of every straight
    drive between areas and of the tables placed before it."""
    drives = [(areas[a], areas[b]) for i, a in enumerate(areas) for b in list(areas)[i + 1 :]]
    placed: dict[str, tuple] = {}
    rects: list = []
    # axis-aligned headings first, then diagonals, then the rest
    order = [0, 4, 8, 12, 2, 6, 10, 14, 1, 3, 5, 7, 9, 11, 13, 15]
    for name in with_table:
        x, y = areas[name]
        best: tuple[float, float, list] | None = None
        for k in order:
            yaw = math.pi * k / 8
            rect = _table_rect(x, y, yaw)
            edges = list(zip(rect, rect[1:] + rect[:1]))
            clear = min(
                [_rect_seg_dist(rect, a, b) - ROBOT_HALF_WIDTH for a, b in drives]
                # the robot stands at the other areas' base poses
                + [_rect_seg_dist(rect, p, p) - 0.6 for n, p in areas.items() if n != name]
                + [
                    _seg_dist(c, d, e, f) - 0.3
                    for r in rects
                    for c, d in zip(r, r[1:] + r[:1])
                    for e, f in edges
                ],
                default=1.0,
            )
            if best is None or clear > best[0] + 1e-9:
                best = (clear, yaw, rect)
            if clear >= 0.25:
                break
        assert best is not None  # order is not empty
        if best[0] < 0:
            raise HtnError.at(
                where_said.get(name),
                f"cannot lay out the simulated kitchen: the table of area '{name}' "
                "would block a drive or another table (areas too close together?)",
            )
        _, yaw, rect = best
        ux, uy = math.cos(yaw), math.sin(yaw)
        mid = TABLE_GAP + TABLE_DEPTH / 2
        placed[name] = (x + ux * mid, y + uy * mid, yaw)
        rects.append(rect)
    return placed
