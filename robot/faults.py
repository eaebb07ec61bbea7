"""Injected faults: ``--faults name=P,...`` parsed once, checked against the
kinds a robot back end can inject (no simulator needed to check them)."""
from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Iterable, Optional

from htn.jshop.language.errors import HtnError


def parse_faults(text: Optional[str], known: Iterable[str]) -> dict[str, float]:
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
    slip: float = 0.0     # object slips out of the gripper: while a grasp lifts it, and
                          # (drawn again for each drive) while the base drives with it
    nav: float = 0.0      # navigation stops short of the goal
    detect: float = 0.0   # object detection misses
    moved: float = 0.0    # a person moves the object (once) just before the robot grasps it

    @classmethod
    def kinds(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))

    @classmethod
    def parse(cls, text: Optional[str]) -> "Faults":
        return cls(**parse_faults(text, cls.kinds()))
