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
from typing import Optional

from jshop.errors import HtnError


@dataclass
class Place:
    name: str
    x: float
    y: float
    theta: float          # radians

    @property
    def pose(self) -> tuple[float, float, float]:
        return self.x, self.y, self.theta


@dataclass
class Furniture:
    name: str
    kind: str
    x: float
    y: float
    approach: str         # name of the Place the robot works from


@dataclass
class Thing:
    name: str
    kind: str
    on: Optional[str] = None           # furniture name
    grasps: tuple = ()


@dataclass
class Person:
    name: str
    x: float
    y: float
    at: Optional[str] = None           # Place where the robot meets them
    can_receive: bool = False


@dataclass
class World:
    places: dict = field(default_factory=dict)
    furniture: dict = field(default_factory=dict)
    things: dict = field(default_factory=dict)
    persons: dict = field(default_factory=dict)
    robot: str = "robot"
    robot_at: Optional[str] = None
    holding: Optional[str] = None
    static_facts: list = field(default_factory=list)   # (pred, args) never changed by actions

    def place(self, name: str) -> Place:
        try:
            return self.places[name]
        except KeyError:
            raise HtnError(f"unknown location '{name}' (no (location {name} x y theta) fact)")


def _num(args, i, what, pos) -> float:
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
                w.places[args[0]] = Place(args[0], _num(args, 1, p, pos), _num(args, 2, p, pos),
                                          math.radians(_num(args, 3, p, pos)))
            elif p == "furniture":
                w.furniture[args[0]] = Furniture(args[0], args[1], _num(args, 2, p, pos),
                                                 _num(args, 3, p, pos), args[4])
            elif p == "object":
                w.things.setdefault(args[0], Thing(args[0], args[1])).kind = args[1]
            elif p == "object_on":
                w.things.setdefault(args[0], Thing(args[0], "object")).on = args[1]
            elif p == "graspable":
                t = w.things.setdefault(args[0], Thing(args[0], "object"))
                t.grasps = t.grasps + (args[1],)
            elif p == "person":
                w.persons.setdefault(args[0], Person(args[0], 0.0, 0.0))
                w.persons[args[0]].x = _num(args, 1, p, pos)
                w.persons[args[0]].y = _num(args, 2, p, pos)
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
            raise HtnError.at(pos, f"({p} ...) has too few arguments")
    if w.robot_at is None:
        raise HtnError("the initial state has no (robot_at ROBOT LOCATION) fact")
    w.place(w.robot_at)
    for f in w.furniture.values():
        w.place(f.approach)
    return w
