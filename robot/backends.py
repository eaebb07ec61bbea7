"""Robot back ends by name: the built-in ones and those of plugins.

``htn run --robot NAME`` (and ``--sim``, short for ``--robot pybullet``) looks
the name up here. A back end is a factory called with a :class:`RobotRequest`
and returning a :class:`~htn.robot.interface.Robot`. Other packages add back
ends through the entry-point group ``htn.robots``: the entry point's name is
the robot's name, its object the factory::

    [project.entry-points."htn.robots"]
    turtle = "my_package.robot:make_robot"

A factory checks its request (unknown fault kinds, a world it cannot build)
by raising :class:`~htn.jshop.language.errors.HtnError`, before anything moves.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError

from .faults import parse_faults


@dataclass
class RobotRequest:
    """What a robot back end is asked to build: the planning domain, the
    problem instance whose initial state is the world, the ``--faults`` text,
    the seed of its random draws, a window or not, and the user functions."""

    domain: S.Domain
    instance: S.ProblemInstance
    faults: str = ""
    seed: int = 0
    gui: bool = False
    functions: Any = None

    def fault_rates(self, known) -> dict[str, float]:
        """The ``--faults`` probabilities, checked against the kinds ``known``."""
        return parse_faults(self.faults, known)


def _pybullet(req: RobotRequest):
    from .faults import Faults

    faults = Faults(**req.fault_rates(Faults.kinds()))
    from . import simulated_robot

    return simulated_robot(req.instance.state, gui=req.gui, faults=faults, seed=req.seed)


def _symbolic(req: RobotRequest):
    from .symbolic import SymbolicRobot

    return SymbolicRobot(
        req.domain, req.instance, req.functions, req.fault_rates(SymbolicRobot.FAULTS), req.seed
    )


def _projection(req: RobotRequest):
    from .projection import FailureRates, ProjectionRobot, world_from_atoms

    # like the other robots, nothing fails unless --faults says so
    rates = FailureRates.none().with_faults(req.faults)
    return ProjectionRobot(world_from_atoms(req.instance.state), seed=req.seed, failures=rates)


@dataclass
class Backend:
    name: str
    factory: Callable
    description: str
    extra: str | None = None  # the install extra it needs ('sim'), if any


BUILTIN = {
    "pybullet": Backend(
        "pybullet",
        _pybullet,
        "PyBullet physics: the domestic robot, or the "
        "two-armed kitchen robot for (area ...) problems",
        "sim",
    ),
    "symbolic": Backend(
        "symbolic",
        _symbolic,
        "the domain's own operators on a symbolic world; any domain (faults: effect=P, fail=P)",
    ),
    "projection": Backend(
        "projection",
        _projection,
        "the fast kinematic projection of the "
        "plan-transformations paper (kitchen and domestic problems)",
    ),
}


def backends() -> dict[str, Backend]:
    """The built-in back ends and those registered by installed plugins."""
    from importlib.metadata import entry_points

    found = dict(BUILTIN)
    for ep in entry_points(group="htn.robots"):
        if ep.name not in found:
            found[ep.name] = Backend(ep.name, _lazy(ep), f"plugin ({ep.value})")
    return found


def _lazy(ep) -> Callable:
    def factory(req: RobotRequest):
        try:
            make = ep.load()
        except ModuleNotFoundError as exc:
            if ep.dist is not None and ep.dist.name == "htn":  # htn's own: its extra, same name
                raise HtnError(
                    f"--robot {ep.name} needs the {ep.name} extra: pip install 'htn[{ep.name}]'"
                ) from exc
            raise HtnError(
                f"robot plugin '{ep.name}' ({ep.value}) failed to load: {type(exc).__name__}: {exc}"
            ) from exc
        except Exception as exc:  # a broken plugin: say which, no traceback
            raise HtnError(
                f"robot plugin '{ep.name}' ({ep.value}) failed to load: {type(exc).__name__}: {exc}"
            ) from exc
        return make(req)

    return factory


def make_robot(name: str, request: RobotRequest):
    """Build the robot back end ``name`` for ``request``."""
    known = backends()
    backend = known.get(name)
    if backend is None:
        raise HtnError(f"--robot: unknown robot '{name}' (known: {', '.join(sorted(known))})")
    return backend.factory(request)
