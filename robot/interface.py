"""The robot interface: skills and checks by name, a clock, and what it observes.

A robot offers **skills** (act on the world) and **checks** (look at the
world), each registered by name with the :func:`skill` and :func:`check`
decorators; the action state machines call them with :meth:`Robot.act` and
:meth:`Robot.check`. A robot that lacks a skill or check answers with an
internal failure (the action ends ``failed``) or an unobservable check (the
monitor does not verify), never with an exception.

A skill returns a :class:`SkillResult` at once (an instantaneous robot, such
as the symbolic or the projected one) or a generator that advances the
simulation by one physics step per ``next()`` and finally returns its
:class:`SkillResult` (the PyBullet robots). The task executor ticks such a
skill, ``steps_per_tick`` physics steps per tick of the behaviour tree, and
runs the action's hold-monitors between ticks; closing the generator preempts
the skill where it is (``finally`` blocks run, the robot then holds its pose).

``SkillResult.ok`` is the robot's own belief that it finished (``False`` only
for an internal failure, e.g. an unreachable arm pose). Whether the effect
really happened is for a monitor to decide with the checks, which look at the
world itself.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any


@dataclass
class SkillResult:
    ok: bool
    detail: str = ""
    data: dict = field(default_factory=dict)


@dataclass
class Caption:
    """What a snapshot shows happened: the step (1-based), its action, the
    attempt, the outcome and the simulated time, and the monitor's detail."""

    step: int
    action: str
    attempt: int
    outcome: str
    sim_time: float
    detail: str = ""

    def lines(self) -> list[str]:
        return [
            f"step {self.step}  {self.action}",
            f"attempt {self.attempt}  {self.outcome}  t = {self.sim_time:.2f} s (simulated)",
            *([self.detail] if self.detail else []),
        ]


@dataclass
class Check:
    """A monitor's observation: did the world show the expected effect?"""

    ok: bool
    detail: str = ""


Ticking = Iterator[None]  # a skill in progress: one physics step per next()
SkillRun = SkillResult | Ticking  # what act() returns: done at once, or ticking


def skill(name: str) -> Callable:
    """Method decorator: register the method as the robot's skill ``name``."""

    def mark(fn):
        fn.htn_skills = (*getattr(fn, "htn_skills", ()), name)
        return fn

    return mark


def check(name: str) -> Callable:
    """Method decorator: register the method as the robot's check ``name``."""

    def mark(fn):
        fn.htn_checks = (*getattr(fn, "htn_checks", ()), name)
        return fn

    return mark


def complete(result: SkillRun) -> SkillResult:
    """Run a skill to its end without ticking (set-up, tests, plugins)."""
    if isinstance(result, SkillResult):
        return result
    while True:
        try:
            next(result)
        except StopIteration as stop:
            return stop.value


class Robot:
    """A robot back end: skills (act), checks (observe) and state estimation.

    Every robot has a clock (``sim_time``), can ``hold`` its pose and report
    what it ``observe``s of the domain's dynamic predicates. A robot whose
    ``executes_operator_model`` is true runs every operator through the
    ``operator`` skill and the ``operator_effects`` check (the symbolic robot).
    Faults a robot injects are appended to ``injected`` (kind, sim time,
    detail), which the task executor turns into ``fault`` events.
    """

    world: Any = None
    sim_time: float = 0.0
    executes_operator_model: bool = False
    steps_per_tick: int = 1  # physics steps a skill advances per tick
    instantaneous: bool = False  # every skill ends as it starts: nothing to hold-monitor
    observes_world: bool = False  # a long-lived planner asks observe() before each goal
    _skills: dict = {}
    _checks: dict = {}

    def __init_subclass__(cls, **kw):
        # collect the marked methods of the whole class hierarchy; a
        # subclass's method overrides by name (the parts a robot holds are
        # objects: its own marked methods offer what they do)
        super().__init_subclass__(**kw)
        cls._skills, cls._checks = {}, {}
        for klass in reversed(cls.__mro__):
            for attr, fn in vars(klass).items():
                for name in getattr(fn, "htn_skills", ()):
                    cls._skills[name] = attr
                for name in getattr(fn, "htn_checks", ()):
                    cls._checks[name] = attr

    # ---- by name
    def act(self, name: str, *args) -> SkillRun:
        """Start skill ``name``: a result, or a generator to tick (see module
        doc). A robot written without the decorator offers its method of the
        same name."""
        fn = getattr(self, self._skills.get(name, name), None)
        if not callable(fn):
            return SkillResult(False, f"{type(self).__name__} cannot {name.replace('_', ' ')}")
        return fn(*args)

    def check(self, name: str, *args) -> Check:
        """Run check ``name`` on the world as it is now (without the
        decorator: the method ``check_NAME``)."""
        fn = getattr(self, self._checks.get(name, f"check_{name}"), None)
        if not callable(fn):
            return Check(
                False, f"{name.replace('_', ' ')} is not observable on {type(self).__name__}"
            )
        return fn(*args)

    @classmethod
    def check_names(cls) -> list[str]:
        return sorted(
            {
                *cls._checks,
                *(a[6:] for a in dir(cls) if a.startswith("check_") and a != "check_names"),
            }
        )

    # ---- control and state estimation
    def apply_internal(self, name: str, args: tuple) -> None:
        """An internal (``!!``) step was applied to the belief state; a robot
        whose world is the operator model applies it too."""

    def hold(self) -> None:
        """Stop all motion and keep the current pose (after a failure)."""

    def observe(self) -> list[tuple[str, tuple]]:
        """Facts of the domain's dynamic predicates, as the robot perceives them."""
        return []

    def inject(self, kind: str, detail: str) -> None:
        """Record a fault this robot injects now (see ``--faults``)."""
        self.__dict__.setdefault("injected", []).append(
            {"kind": kind, "sim_t": round(self.sim_time, 4), "detail": detail}
        )

    def injected_faults(self) -> list[dict]:
        """The faults injected so far (kind, sim_t, detail), oldest first."""
        return list(getattr(self, "injected", []))

    def close(self) -> None:
        pass

    def snapshot(self, path: str, label: Caption | None = None) -> str | None:
        """Save a picture of the world as PNG at ``path``, with ``label``
        drawn on it; the path, or None for a robot without a camera."""
        return None

    def camera_frame(self, width: int = 320, height: int = 240) -> bytes | None:
        """A camera image of the world now, as JPEG bytes (None: no camera).
        Called between two ticks, in the thread that runs the robot."""
        return None
