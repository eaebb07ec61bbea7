"""Injected faults: ``--faults name=P,...`` parsed once, checked against the
kinds a robot back end can inject (no simulator needed to check them)."""

from __future__ import annotations

import random
from collections.abc import Callable, Iterable
from dataclasses import dataclass, fields

from htn.jshop.language.errors import HtnError


def parse_faults(text: str | None, known: Iterable[str]) -> dict[str, float]:
    """``"slip=0.3,nav=0.1"`` -> ``{"slip": 0.3, "nav": 0.1}``; every name must
    be one of ``known`` and every value a probability."""
    known = tuple(known)
    out: dict[str, float] = {}
    for part in (text or "").split(","):
        if not part.strip():
            continue
        name, sep, value = part.partition("=")
        name = name.strip()
        if name not in known:
            kinds = ", ".join(known) if known else "none"
            raise HtnError(f"--faults: unknown fault '{name}' (this robot injects: {kinds})")
        try:
            p = float(value) if sep else float("nan")
        except ValueError:
            p = float("nan")
        if p != p:
            raise HtnError(f"--faults: '{part.strip()}' needs a probability, e.g. {name}=0.3")
        if not 0.0 <= p <= 1.0:
            raise HtnError(f"--faults: {name}={value.strip()} is not a probability in [0, 1]")
        out[name] = p
    return out


@dataclass
class Faults:
    """Probabilities of the PyBullet robots' injected faults (each in [0, 1])."""

    slip: float = 0.0  # object slips out of the gripper: while a grasp lifts it, and
    # (drawn again for each drive) while the base drives with it
    nav: float = 0.0  # navigation stops short of the goal
    detect: float = 0.0  # object detection misses
    moved: float = 0.0  # a person moves the object (once) just before the robot grasps it

    @classmethod
    def kinds(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    @classmethod
    def parse(cls, text: str | None) -> Faults:
        return cls(**parse_faults(text, cls.kinds()))


class FaultDraws:
    """The seeded draws of a simulated robot's faults, and the record of those
    injected. One random generator serves all the robot's parts (and the
    perception noise): the order of the draws is the run's, so the same seed
    gives the same run."""

    def __init__(self, faults: Faults, seed: int, clock: Callable[[], float]):
        self.faults = faults
        self.rng = random.Random(seed)
        self.injected: list[dict] = []  # kind, sim_t, detail: for the log and the tests
        self._clock = clock
        self._moved: set[str] = set()  # objects somebody already took away

    def happens(self, kind: str) -> bool:
        """Does fault ``kind`` happen now? Draws only when its probability is not 0."""
        p = getattr(self.faults, kind)
        return bool(p) and self.rng.random() < p

    def moved_once(self, obj: str) -> bool:
        """The ``moved`` fault: somebody takes ``obj`` away, once at most."""
        if self.faults.moved and obj not in self._moved and self.happens("moved"):
            self._moved.add(obj)
            return True
        return False

    def inject(self, kind: str, detail: str) -> None:
        self.injected.append({"kind": kind, "sim_t": round(self._clock(), 4), "detail": detail})
