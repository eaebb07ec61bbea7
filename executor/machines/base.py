"""Action state machines: one per operator, one life cycle for all.

As in the paper (section 4), every operator is executed by a small state
machine with three states: **execute** the action, run its **monitor**, and
**report**, with one of the outcomes of :class:`htn.executor.outcome.Outcome`.

An :class:`ActionMachine` says what to execute, what to monitor afterwards,
and what must hold while it executes (:meth:`ActionMachine.holds`); the task
executor runs it as a behaviour tree (:mod:`htn.executor.behaviours`).
Registering one for a new operator is a few lines::

    @action("!wave")
    class Wave(ActionMachine):
        def execute(self, robot, hand):
            return robot.act("wave", hand)
        def monitor(self, robot, hand):
            return robot.check("waving", hand)

``execute`` may return a :class:`~htn.robot.interface.SkillResult` at once
or a generator that the executor ticks (see :mod:`htn.robot.interface`).
Other packages register machines through the entry-point group
``htn.actions``: each entry point names a module (importing it runs its
``@action`` decorators) or a function called once with no arguments. They
are loaded the first time a machine is looked up. The machines for the
bundled domains are in :mod:`htn.executor.machines.domestic` and
:mod:`htn.executor.machines.kitchen`.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module
from typing import Any, TypeVar

from htn.robot.interface import Check, Robot, SkillResult, SkillRun

HoldMonitor = tuple[str, Callable[[], Check]]  # (what must hold, how to check it)


class ActionMachine:
    """Execute -> monitor -> report, for one operator instance.

    Subclasses define :meth:`execute` (start a robot skill) and
    :meth:`monitor` (check the world afterwards), and may define
    :meth:`holds` (conditions checked on every tick while the action runs);
    arguments are the plan step's parameters.
    """

    name = ""

    def execute(self, robot: Robot, *args: Any) -> SkillRun:  # pragma: no cover - abstract
        raise NotImplementedError

    def monitor(self, robot: Robot, *args: Any) -> Check:  # pragma: no cover - abstract
        raise NotImplementedError

    def holds(self, robot: Robot, *args: Any) -> list[HoldMonitor]:
        """Hold-monitors of this action: what must stay true while it executes."""
        return []


# (domain or None, operator) -> machine class
REGISTRY: dict[tuple[str | None, str], type[ActionMachine]] = {}
M = TypeVar("M", bound=type[ActionMachine])  # a machine class, as the decorator returns it


def action(operator: str, domain: str | None = None) -> Callable[[M], M]:
    """Class decorator: register an :class:`ActionMachine` for an operator name,
    for every domain or (``domain=``) for one domain whose operator of the same
    name means something else."""

    def register(cls: M) -> M:
        cls.name = operator
        REGISTRY[(domain, operator)] = cls
        return cls

    return register


CARRIED: dict[str | None, str] = {}  # domain or None -> predicate of what is carried


def carried_by(predicate: str, domain: str | None = None) -> None:
    """Declare that in the belief state ``(predicate ... ?obj)`` means the
    robot carries ``?obj`` (for every domain, or for one): while any action
    runs, the task dispatcher then checks on every tick that what the robot
    carries stays in its gripper (the robot's ``still_held`` check)."""
    CARRIED[domain] = predicate


def carry_predicate(domain: str | None) -> str | None:
    """The predicate of what the robot carries in ``domain``, if declared."""
    load_plugins()
    return CARRIED.get(domain) or CARRIED.get(None)


# the machines of the bundled domains, loaded like plugins (by name)
BUNDLED = ("htn.executor.machines.domestic", "htn.executor.machines.kitchen")
_plugins_loaded = False


def load_plugins() -> None:
    """Load the bundled machines and the ``htn.actions`` entry points (once)."""
    global _plugins_loaded
    if _plugins_loaded:
        return
    _plugins_loaded = True
    import inspect
    from importlib.metadata import entry_points

    from htn.jshop.language.errors import HtnError

    for module in BUNDLED:  # their @action decorators register
        import_module(module)
    for ep in entry_points(group="htn.actions"):
        try:
            obj = ep.load()
            if callable(obj) and not inspect.isclass(obj):
                obj()
        except Exception as exc:  # a broken plugin: say which, no traceback
            raise HtnError(
                f"action plugin '{ep.name}' ({ep.value}) failed to load: "
                f"{type(exc).__name__}: {exc}"
            ) from exc


def machine_for(
    operator: str, domain: str | None = None, robot: Robot | None = None
) -> ActionMachine | None:
    """The action state machine for an operator: the operator model's on a
    robot that executes it, else the one registered for this domain, else
    the one registered for every domain, else None."""
    if robot is not None and robot.executes_operator_model:
        return OperatorModelAction(operator)
    load_plugins()
    cls = REGISTRY.get((domain, operator)) or REGISTRY.get((None, operator))
    return cls() if cls else None


class OperatorModelAction(ActionMachine):
    """Any operator, on a robot whose world is the domain's operator model:
    execute applies the operator's effects, the monitor checks its add and
    delete lists against the world (see :mod:`htn.robot.symbolic`)."""

    def __init__(self, operator: str):
        self.name = operator

    def execute(self, robot: Robot, *args: Any) -> SkillRun:
        return robot.act("operator", self.name, args)

    def monitor(self, robot: Robot, *args: Any) -> Check:
        return robot.check("operator_effects", self.name, args)


def all_of(*checks: Check) -> Check:
    """One observation from several: ok when all are; the details of the failing ones."""
    bad = [c for c in checks if not c.ok]
    return Check(not bad, "; ".join(c.detail for c in (bad or checks)))


__all__ = [
    "ActionMachine",
    "action",
    "carried_by",
    "machine_for",
    "all_of",
    "SkillResult",
    "Check",
    "HoldMonitor",
]
