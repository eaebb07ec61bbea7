"""Fast projection: a kinematic world behind the same robot interface.

Like the projection of the plan-transformations paper, the base "teleports"
between poses and nothing is simulated physically: base poses at an area,
grasp points and arm trajectories are sampled at random (seeded), and actions
fail with configurable probabilities. As in the paper, every action samples
its own base pose (searching, fetching and delivering each reposition the
robot within the area), so manipulation also costs some navigation. A failed action finishes but leaves its
effect absent, so the executor's monitors see it and retry, exactly as on the
simulated robot. Each run records:

* ``navigation``: the sum of base displacements (m);
* ``manipulation``: the distance travelled by the gripper key points (m);
* ``actions``: the number of action attempts; ``failures``: the failed ones;
* ``sim_time``: a nominal duration (base 0.5 m/s, arm 0.25 m/s, 1 s per action).

Used for the kitchen domain (areas, two arms, drawers, a tray); the places of
a domestic problem (``location``) work too.
"""

from __future__ import annotations

import math
import random
from dataclasses import dataclass, field, fields, replace

from htn.jshop.language.errors import HtnError

from .faults import parse_faults
from .interface import Check, Robot, SkillResult, check, skill
from .world import number_arg

ARM_REST = {"left": (0.1, 0.35, 0.9), "right": (0.1, -0.35, 0.9)}  # relative to the base
BASE_SPEED, ARM_SPEED, ACTION_TIME = 0.5, 0.25, 1.0
SURFACE_Z = 0.85


@dataclass
class FailureRates:
    """Probabilities that an action fails (its effect does not happen)."""

    navigate: float = 0.02
    detect: float = 0.03
    grasp: float = 0.04
    grasp_busy: float = 0.10  # grasping while the other arm already holds something
    place: float = 0.02
    container: float = 0.03
    tray: float = 0.05

    @classmethod
    def none(cls) -> FailureRates:
        return cls(0, 0, 0, 0, 0, 0, 0)

    @classmethod
    def kinds(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    def with_faults(self, text: str | None) -> FailureRates:
        """These rates, with the ``--faults`` probabilities ``text`` gives
        (``grasp=0.3,navigate=0.1``) in place of theirs."""
        return replace(self, **parse_faults(text, self.kinds()))


@dataclass
class Metrics:
    navigation: float = 0.0
    manipulation: float = 0.0
    actions: int = 0
    failures: int = 0
    sim_time: float = 0.0

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class ProjectedWorld:
    places: dict = field(default_factory=dict)  # name -> (x, y)
    where: dict = field(default_factory=dict)  # object -> area or container or tray
    containers: dict = field(default_factory=dict)  # container -> area
    trays: dict = field(default_factory=dict)  # tray -> area (None while carried)
    start: str | None = None


def world_from_atoms(atoms) -> ProjectedWorld:
    """The projection's world from a state's atoms; an area's coordinates
    that are no numbers, or an atom with too few arguments, is an error at
    the atom."""
    w = ProjectedWorld()
    for a in atoms:
        p, args, pos = a.pred, a.args, getattr(a, "pos", None)
        try:
            if p in ("area", "location"):
                w.places[args[0]] = (number_arg(args, 1, p, pos), number_arg(args, 2, p, pos))
            elif p in ("at", "in", "object_on"):
                w.where[args[0]] = args[1]
            elif p == "container":
                w.containers[args[0]] = args[1]
            elif p == "tray":
                w.trays[args[0]] = args[1]
            elif p in ("robot-at", "robot_at"):
                w.start = args[-1]
        except IndexError:
            raise HtnError.at(pos, f"({p} ...) has too few arguments") from None
    return w


class ProjectionRobot(Robot):
    """A two-armed robot in a projected world; deterministic for a seed."""

    instantaneous = True

    def __init__(
        self,
        world: ProjectedWorld,
        seed: int = 0,
        failures: FailureRates | None = None,
        pose_noise: float = 0.25,
    ):
        self.world = world
        self.rng = random.Random(seed)
        self.rates = failures or FailureRates()
        self.noise = pose_noise
        self.metrics = Metrics()
        self.where = dict(world.where)
        self.trays = dict(world.trays)
        self.opened: set = set()
        self.hands: dict = {"left": None, "right": None}
        self.carrying_tray: str | None = None
        self.detections: set = set()
        self.spoken: list = []
        self.at = world.start
        x, y = world.places.get(world.start, (0.0, 0.0))
        self.base = (x, y)

    # ------------------------------------------------------------ bookkeeping
    @property
    def sim_time(self) -> float:
        return self.metrics.sim_time

    @sim_time.setter
    def sim_time(self, value: float) -> None:  # Robot.sim_time is writeable
        self.metrics.sim_time = value

    def _act(self, kind: str) -> bool:
        """Count an action attempt; True if it fails (probability by kind)."""
        self.metrics.actions += 1
        self.metrics.sim_time += ACTION_TIME
        if self.rng.random() < getattr(self.rates, kind):
            self.metrics.failures += 1
            return True
        return False

    def _sample_near(self, place: str, spread: float) -> tuple[float, float]:
        x, y = self.world.places[place]
        return x + self.rng.gauss(0, spread), y + self.rng.gauss(0, spread)

    def _reposition(self, place: str | None) -> None:
        """Move the base to a pose sampled for this action near ``place``."""
        if place is None or place not in self.world.places:
            return
        x, y = self._sample_near(place, self.noise * 2)
        d = math.dist(self.base, (x, y))
        self.metrics.navigation += d
        self.metrics.sim_time += d / BASE_SPEED
        self.base = (x, y)

    def _arm_motion(self, arm: str, place: str | None) -> None:
        """Rest -> pre-grasp -> grasp -> lift -> rest for one gripper, from a
        base pose sampled for this action."""
        self._reposition(place)
        bx, by = self.base
        rx, ry, rz = ARM_REST[arm or "right"]
        tx, ty = (
            self._sample_near(place, 0.15)
            if place is not None and place in self.world.places
            else (bx + 0.6, by)
        )
        # the target is within reach in front of the robot: pull it to 0.7 m
        d = math.hypot(tx - bx, ty - by) or 1.0
        reach = min(d, 0.55 + self.rng.uniform(0.0, 0.2))
        gx, gy, gz = bx + (tx - bx) * reach / d, by + (ty - by) * reach / d, SURFACE_Z
        rest = (bx + rx, by + ry, rz)
        pts = [rest, (gx, gy, gz + 0.15), (gx, gy, gz), (gx, gy, gz + 0.15), rest]
        dist = sum(math.dist(a, b) for a, b in zip(pts, pts[1:]))
        self.metrics.manipulation += dist
        self.metrics.sim_time += dist / ARM_SPEED

    def _area_of(self, where: str) -> str:
        return self.world.containers.get(where, self.trays.get(where, where))

    # ------------------------------------------------------------ skills
    @skill("move_base")
    def move_base(self, place: str) -> SkillResult:
        if place not in self.world.places:
            return SkillResult(False, f"unknown place {place}")
        failed = self._act("navigate")
        x, y = self._sample_near(place, self.noise)
        if failed:  # stops somewhere on the way
            f = self.rng.uniform(0.3, 0.8)
            x, y = self.base[0] + (x - self.base[0]) * f, self.base[1] + (y - self.base[1]) * f
        d = math.dist(self.base, (x, y))
        self.metrics.navigation += d
        self.metrics.sim_time += d / BASE_SPEED
        self.base = (x, y)
        self.at = None if failed else place
        return SkillResult(True, f"at {x:.2f} {y:.2f}")

    @skill("detect_object")
    def detect_object(self, obj: str, where: str) -> SkillResult:
        failed = self._act("detect")
        if not failed and (
            self.where.get(obj) in (where, *self._contents_of(where))
            or self.trays.get(obj) == where
        ):
            self.detections.add(obj)
        return SkillResult(True, "looked")

    def _contents_of(self, area: str) -> tuple:
        return tuple(c for c, a in self.world.containers.items() if a == area)

    @skill("grasp")
    def grasp(self, obj: str, where: str, arm: str | None = None) -> SkillResult:
        arm = arm or ("left" if self.hands["left"] is None else "right")
        if self.hands.get(arm) is not None:
            return SkillResult(False, f"the {arm} hand is not free")
        busy = any(o for a, o in self.hands.items() if a != arm)
        failed = self._act("grasp_busy" if busy else "grasp")
        self._arm_motion(arm, self._area_of(where))
        if where in self.world.containers and where not in self.opened:
            return SkillResult(True, f"{where} is closed")
        if not failed and self.where.get(obj) == where:
            self.hands[arm] = obj
            self.where[obj] = ("hand", arm)
        return SkillResult(True, f"{arm} gripper closed")

    @skill("place_object")
    def place_object(self, obj: str, where: str, arm: str | None = None) -> SkillResult:
        arm = arm or next((a for a, o in self.hands.items() if o == obj), None)
        if arm is None or self.hands.get(arm) != obj:
            return SkillResult(True, f"{obj} is not in a hand")
        failed = self._act("place")
        self._arm_motion(arm, where)
        if not failed:
            self.hands[arm] = None
            self.where[obj] = where
        return SkillResult(True, f"{arm} gripper opened")

    @skill("open_container")
    def open_container(self, container: str) -> SkillResult:
        failed = self._act("container")
        self._arm_motion("right", self._area_of(container))
        if not failed:
            self.opened.add(container)
        return SkillResult(True, "pulled")

    @skill("close_container")
    def close_container(self, container: str) -> SkillResult:
        failed = self._act("container")
        self._arm_motion("right", self._area_of(container))
        if not failed:
            self.opened.discard(container)
        return SkillResult(True, "pushed")

    @skill("put_on_tray")
    def put_on_tray(self, obj: str, tray: str, arm: str | None = None) -> SkillResult:
        arm = arm or next((a for a, o in self.hands.items() if o == obj), None)
        if arm is None:
            return SkillResult(True, f"{obj} is not in a hand")
        failed = self._act("place")
        self._arm_motion(arm, "")  # the tray is beside the robot: no new base pose
        if not failed:
            self.hands[arm] = None
            self.where[obj] = tray
        return SkillResult(True, "released over the tray")

    @skill("lift_tray")
    def lift_tray(self, tray: str) -> SkillResult:
        failed = self._act("tray")
        self._arm_motion("left", self.trays.get(tray) or self.at)
        self._arm_motion("right", "")  # both arms from the same base pose
        if not failed:
            self.carrying_tray, self.trays[tray] = tray, None
        return SkillResult(True, "both grippers closed on the tray")

    @skill("lower_tray")
    def lower_tray(self, tray: str, where: str) -> SkillResult:
        failed = self._act("tray")
        self._arm_motion("left", where)
        self._arm_motion("right", "")
        if not failed and self.carrying_tray == tray:
            self.carrying_tray, self.trays[tray] = None, where
        return SkillResult(True, "tray lowered")

    @skill("take_from_tray")
    def take_from_tray(self, obj: str, tray: str, arm: str | None = None) -> SkillResult:
        arm = arm or ("left" if self.hands["left"] is None else "right")
        failed = self._act("grasp")
        self._arm_motion(arm, "")  # the tray is beside the robot
        if not failed and self.where.get(obj) == tray and self.hands.get(arm) is None:
            self.hands[arm] = obj
            self.where[obj] = ("hand", arm)
        return SkillResult(True, f"{arm} gripper closed")

    @skill("find_person")
    def find_person(self, person: str) -> SkillResult:
        self._act("detect")
        self.detections.add(person)
        return SkillResult(True, "looked")

    @skill("hand_over")
    def hand_over(self, obj: str, person: str) -> SkillResult:
        arm = next((a for a, o in self.hands.items() if o == obj), None)
        self._act("place")
        if arm is not None:
            self.hands[arm] = None
            self.where[obj] = person
        return SkillResult(True, "handed")

    @skill("say")
    def say(self, message: str) -> SkillResult:
        self.metrics.actions += 1
        self.metrics.sim_time += ACTION_TIME
        self.spoken.append(message)
        return SkillResult(True, "said")

    def hold(self) -> None:
        pass

    # ------------------------------------------------------------ checks
    @check("base_at")
    def check_base_at(self, place: str) -> Check:
        return Check(self.at == place, f"at {self.at or 'somewhere on the way'}")

    @check("no_collision")
    def check_no_collision(self) -> Check:
        return Check(True, "projection has no collisions")

    @check("still_held")
    @check("in_gripper")
    def check_in_gripper(self, obj: str) -> Check:
        return Check(
            obj in self.hands.values(),
            f"{obj} {'in' if obj in self.hands.values() else 'not in'} a hand",
        )

    @check("on")
    def check_on(self, obj: str, where: str) -> Check:
        return Check(self.where.get(obj) == where, f"{obj} at {self.where.get(obj)}")

    @check("handed")
    def check_handed(self, obj: str, person: str) -> Check:
        return Check(self.where.get(obj) == person, f"{obj} at {self.where.get(obj)}")

    @check("person_visible")
    def check_person_visible(self, person: str) -> Check:
        return Check(person in self.detections, "seen")

    @check("detection")
    def check_detection(self, obj: str) -> Check:
        return Check(obj in self.detections, "seen" if obj in self.detections else "not seen")

    @check("said")
    def check_said(self, message: str) -> Check:
        return Check(bool(self.spoken) and self.spoken[-1] == message, "spoken")

    @check("opened")
    def check_opened(self, container: str, opened: bool) -> Check:
        return Check(
            (container in self.opened) == opened,
            f"{container} is {'open' if container in self.opened else 'closed'}",
        )

    @check("on_tray")
    def check_on_tray(self, obj: str, tray: str) -> Check:
        return Check(self.where.get(obj) == tray, f"{obj} at {self.where.get(obj)}")

    @check("tray_carried")
    def check_tray_carried(self, tray: str, carried: bool, where: str | None = None) -> Check:
        ok = (self.carrying_tray == tray) if carried else (self.trays.get(tray) == where)
        return Check(ok, f"tray at {self.trays.get(tray)}")

    def observe(self) -> list[tuple[str, tuple]]:
        facts: list[tuple[str, tuple]] = [("robot-at", (self.at,))] if self.at else []
        for obj, w in self.where.items():
            if isinstance(w, tuple):
                facts.append(("holding", (w[1], obj)))
            elif w in self.world.containers:
                facts.append(("in", (obj, w)))
            elif w in self.trays:
                facts.append(("on-tray", (obj, w)))
            else:
                facts.append(("at", (obj, w)))
        facts += [("free", (a,)) for a, o in self.hands.items() if o is None]
        facts += [("opened", (c,)) for c in self.opened]
        return facts
