"""The run use case: execute a plan's task tree with per-action monitoring on
a robot (``htn run``; the paper's task management, section 4).

:func:`run` does it in one call. A program that must act between the checks
and the first tick (show the behaviour tree, take snapshots, stop the run
from a signal handler or another thread) uses :func:`prepare`, which reads
and checks everything and builds the robot, and then :meth:`Execution.begin`
(the log and its header, the task dispatcher) and :meth:`Execution.execute`.

The plan's task tree is the one its plan file holds (:mod:`htn.jshop.plans.planfile`),
or ``Plan.tree`` for a plan object; a plan without one gets one by planning
again (:func:`htn.jshop.checks.recover.recover_tree`), which
:attr:`Execution.notes` says. Nothing here prints, exits or handles signals:
Ctrl-C (a ``KeyboardInterrupt``) during the run halts it, and the result
says ``interrupted``; a program that halts it for another goal
(:meth:`Execution.halt` with ``outcome="preempted"``, as
:class:`htn.api.agent.Agent` does) makes it say ``preempted``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from types import TracebackType
from typing import TYPE_CHECKING, Any

from htn.executor.dispatcher import RunSummary, TaskDispatcher
from htn.executor.log import EventLog, event_line, run_header
from htn.executor.machines import machine_for
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import Guard
from htn.robot.backends import RobotRequest, make_robot
from htn.robot.interface import Robot

from .extras import check_display, require_robot_extra
from .inputs import path_of
from .run_inputs import LoggedRun, RunInputs, read_run_log, run_inputs
from .run_outputs import RunOutputs

if TYPE_CHECKING:
    from htn.executor.behaviours import ActionContext
    from htn.jshop.plans.plan import Step

    from .inputs import DomainInput, FunctionsInput, ProblemInput, StrPath
    from .run_inputs import PlanInput, RetriesInput

__all__ = ["run", "prepare", "Execution", "RunResult", "read_run_log", "LoggedRun", "event_line"]

Listener = Callable[[dict[str, Any]], None]
# a fact the run believes: (pred, args)
BelievedFact = tuple[str, tuple[Any, ...]]


@dataclass
class RunResult:
    """How a run ended: ``summary`` (result, steps verified, retries, replans,
    simulated time, the step that ended it), every event as logged, the plan
    as executed (repairs included), and the notes of :attr:`Execution.notes`."""

    summary: RunSummary
    events: list[dict[str, Any]] = field(default_factory=list)
    plan: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    @property
    def result(self) -> str:
        """``verified``, ``failed``, ``aborted``, ``interrupted`` or ``preempted``."""
        return self.summary.result

    @property
    def ok(self) -> bool:
        return self.summary.result == "verified"


def run(
    plan: PlanInput,
    *,
    robot: str | Robot,
    domain: DomainInput | None = None,
    problem: ProblemInput | None = None,
    functions: FunctionsInput = None,
    plan_index: int = 1,
    faults: str = "",
    seed: int = 0,
    retries: RetriesInput = None,
    replan: bool = False,
    log: StrPath | None = None,
    on_event: Listener | None = None,
    gui: bool = False,
    argv: list[str] | None = None,
    stops: Guard | None = None,
) -> RunResult:
    """Execute ``plan`` on ``robot`` and return how it ended.

    ``plan``: a plan file's path (as ``htn plan -o`` writes it), a
    :class:`~htn.jshop.plans.planfile.PlanFile`, or a
    :class:`~htn.jshop.plans.plan.Plan` (e.g. from :func:`htn.plan`; then
    ``domain`` and ``problem`` are required). ``domain``, ``problem``,
    ``functions``: paths or loaded objects (default: those the plan file
    names). ``plan_index``: which plan of the file (1-based).

    ``robot``: a registered back end's name (``"symbolic"``, ``"projection"``,
    ``"pybullet"``, or a plugin's), built for the problem with ``faults``
    (``"effect=0.2"``), ``seed`` and ``gui``; or a program's own
    :class:`~htn.robot.interface.Robot` object, used as it is (it injects its
    own faults, and is not closed here).

    ``retries``: retry limits by operator (``{"grasp": 3}`` or ``"grasp=3"``)
    over those of the domain's ``.toml``. ``replan``: repair a failed or
    aborted action by re-planning the smallest enclosing task from the
    observed state. ``log``: a path for the event log (JSON lines, the
    ``header`` first; ``htn run --from-log`` repeats the run from it).
    ``on_event``: called with every event (a dict, as logged) as it happens.
    ``argv``: the command line the header records (None: a program's call).
    ``stops``: the command's :class:`htn.process.Stops` (the user functions
    run under them).
    """
    execution = prepare(
        plan,
        robot=robot,
        domain=domain,
        problem=problem,
        functions=functions,
        plan_index=plan_index,
        faults=faults,
        seed=seed,
        retries=retries,
        replan=replan,
        log=log,
        on_event=on_event,
        gui=gui,
        stops=stops,
    )
    with execution:
        execution.begin(argv)
        try:
            return execution.execute()
        except KeyboardInterrupt as exc:  # outside the ticks: end the log in order
            return execution.interrupted(str(exc))


def robots() -> list[str]:
    """The names of the robot back ends (``htn run --robot NAME``), plugins' too."""
    from htn.robot.backends import backends

    return sorted(backends())


def prepare(
    plan: PlanInput,
    *,
    robot: str | Robot,
    domain: DomainInput | None = None,
    problem: ProblemInput | None = None,
    functions: FunctionsInput = None,
    plan_index: int = 1,
    faults: str = "",
    seed: int = 0,
    retries: RetriesInput = None,
    replan: bool = False,
    log: StrPath | None = None,
    on_event: Listener | None = None,
    gui: bool = False,
    stops: Guard | None = None,
    bt_dot: StrPath | None = None,
    snapshots: StrPath | None = None,
    read: Iterable[str | None] = (),
) -> Execution:
    """Everything :func:`run` does before the log begins: read and check the
    inputs (every step ground and applicable in turn, the retry limits, the
    task tree, the outputs' paths), build the robot and check that every step
    has an action state machine on it. Nothing has moved yet; the caller then
    calls :meth:`Execution.begin` and :meth:`Execution.execute` (or closes
    it), best in a ``with`` block.

    ``bt_dot``: a file for the behaviour tree in DOT, written when the run
    begins and again after it if it was repaired; ``snapshots``: a folder
    for a labelled camera image per action attempt (a robot with a camera);
    ``read``: other files the caller read for this run (a log it repeats),
    which no output may overwrite."""
    outputs = RunOutputs(
        None if log is None else str(log),
        str(bt_dot) if bt_dot else None,
        str(snapshots) if snapshots else None,
    )
    log = outputs.log
    outputs.check(
        [
            path_of(plan) or getattr(plan, "path", None),
            path_of(domain),
            path_of(problem),
            path_of(functions),
            *read,
        ]
    )
    if isinstance(robot, str):
        require_robot_extra(robot, f"the {robot} robot")
        if gui:
            check_display()
    elif isinstance(robot, Robot):
        if faults or gui:
            raise HtnError(
                "faults and gui are for a robot built by name; a robot object "
                "injects its own faults"
            )
    else:
        raise HtnError(f"robot: give a robot's name or a Robot object, not {type(robot).__name__}")
    inputs = run_inputs(plan, domain, problem, functions, plan_index, retries, stops)
    bot: Robot
    if isinstance(robot, str):
        name = robot
        bot = make_robot(
            name,
            RobotRequest(inputs.domain, inputs.instance, faults or "", seed, gui, inputs.functions),
        )
        owned = True
    else:
        bot, name, owned = robot, type(robot).__name__, False
    execution = Execution(inputs, bot, name, owned, faults or "", seed, replan, outputs, on_event)
    try:
        execution.check_machines()
        outputs.prepare_snapshots(bot, name)
    except BaseException:
        execution.close()
        raise
    return execution


class Execution:
    """A run, prepared: :meth:`begin`, :meth:`execute`, then :meth:`close`
    (or use it as a context manager, which closes it and logs an error that
    ended it). :meth:`halt` stops it between two ticks, from anywhere."""

    def __init__(
        self,
        inputs: RunInputs,
        robot: Robot,
        robot_name: str,
        owned: bool,
        faults: str,
        seed: int,
        replan: bool,
        outputs: RunOutputs,
        on_event: Listener | None,
    ) -> None:
        self.inputs = inputs
        self.robot = robot
        self.robot_name = robot_name
        self.owned = owned  # built here, so closed here
        self.faults, self.seed, self.replan = faults, seed, replan
        self.outputs = outputs
        self.log_path = outputs.log
        self.listeners: list[Listener] = [on_event] if on_event else []
        self.log: EventLog | None = None
        self.dispatcher: TaskDispatcher | None = None
        self._halt: tuple[str, str] | None = None  # (why, outcome), before it begins
        self._adopted: tuple[int, str] | None = None  # (count, detail), see adopt()
        self._extra: dict[str, Any] = {}  # see annotate()
        self._closed = False

    @property
    def notes(self) -> list[str]:
        """One line each: what the run had to do that its input did not say
        (a task tree recovered by planning again)."""
        return self.inputs.notes

    @property
    def steps(self) -> list[Step]:
        return self.inputs.plan.steps

    def check_machines(self) -> None:
        """Every step that is not internal has an action state machine for
        this robot (or the robot runs the operator model)."""
        where = self.inputs.plan_file
        for s in self.steps:
            if not s.internal and machine_for(s.name, self.inputs.domain.name, self.robot) is None:
                raise HtnError(
                    f"no action state machine is registered for {s.name} "
                    f"(try --robot symbolic, or add one: entry points "
                    f"'htn.actions')",
                    where,
                    s.line or None,
                    1 if s.line else None,
                )

    def listen(self, listener: Listener) -> None:
        """Call ``listener`` with every event from now on."""
        if self.log is not None:
            self.log.listeners.append(listener)
        else:
            self.listeners.append(listener)

    def begin(self, argv: list[str] | None = None) -> TaskDispatcher:
        """Open the log, write its header (``argv``: the command line it
        records) and build the task dispatcher on the plan's tree."""
        i = self.inputs
        robot = self.robot
        self.log = EventLog(self.log_path, clock=lambda: robot.sim_time)
        self.log.listeners.extend(self.listeners)
        self.log.emit(
            None,
            None,
            "header",
            None,
            "",
            **run_header(
                i.plan_file,
                i.plan_sha256,
                i.plan_index,
                i.files["domain"],
                i.files["problem"],
                i.files["functions"],
                self.robot_name,
                self.seed,
                self.faults,
                i.limits,
                self.replan,
                argv=argv,
                digests={
                    "domain": i.domain.sha256 or None,
                    "problem": i.problem.sha256 or None,
                    "functions": i.functions.sha256,
                },
            ),
        )
        self.dispatcher = TaskDispatcher(
            robot,
            i.domain,
            i.instance,
            i.plan.steps,
            i.limits,
            self.log,
            replan=self.replan,
            functions=i.functions,
            tree=i.tree,
        )
        self.dispatcher.summary_extra.update(self._extra)
        if self._adopted:
            self.dispatcher.adopt(*self._adopted)
        if self._halt:
            self.dispatcher.halt(*self._halt)
        snapshots = self.outputs.snapshot_listener(robot)
        if snapshots is not None:
            self.listen(snapshots)
        self.outputs.write_dot(self.dispatcher.root)
        return self.dispatcher

    def execute(self) -> RunResult:
        """Tick the behaviour tree until the plan is verified, an action fails
        or is aborted (and cannot be repaired), or the run is halted."""
        dispatcher = self.dispatcher if self.dispatcher is not None else self.begin()
        summary = dispatcher.run()
        if summary.replans:  # the tree was repaired: its DOT again
            self.outputs.write_dot(dispatcher.root)
        return self._result(summary)

    def halt(
        self, why: str = "", outcome: str = "interrupted", after: ActionContext | None = None
    ) -> bool:
        """Stop the run before its next tick (safe from a signal handler or
        another thread); ``why`` is logged with the ``interrupted`` event
        and the summary, whose result is ``outcome``: ``interrupted`` (a
        user's stop) or ``preempted`` (a program halts it for another goal).
        ``after``: the context of the running action (from
        :meth:`running_action`), which then goes on to its end; the run
        halts before the next action begins.
        True while a tick runs (the halt takes effect when it ends), else
        False (a signal handler raises its interrupt too: see
        :class:`htn.process.Stops`)."""
        if self.dispatcher is not None:
            return self.dispatcher.halt(why, outcome, after)
        self._halt = (why or "stopped by the user", outcome)
        return False

    def running_action(self) -> tuple[ActionContext, list[BelievedFact]] | None:
        """``(context, facts)`` of the action running now (its context, with
        ``text``, the step; the facts the run believed as it began, ``(pred,
        args)`` pairs), or None; safe from any thread."""
        return None if self.dispatcher is None else self.dispatcher.running_action()

    def last_verified(self) -> ActionContext | None:
        """The context of the step verified last, or None."""
        done = self.dispatcher.done if self.dispatcher is not None else []
        return done[-1] if done else None

    def adopt(self, count: int, detail: str) -> None:
        """Before :meth:`begin`: the plan's first ``count`` steps were
        executed and verified already (an action that went on from a
        preempted run): the run logs them ``verified`` (with ``detail``) and
        starts after them; the plan is checked from the state before them."""
        self._adopted = (count, detail)

    def annotate(self, **fields: Any) -> None:
        """Before :meth:`begin`: more fields for the log's ``summary`` event."""
        self._extra.update(fields)

    def pending_tasks(self) -> list[str]:
        """The plan's top-level tasks not completed (a task partially
        executed counts as not completed), as source text: what a run that
        goes on from this one's end must still do."""
        from htn.executor.repair import pending_tasks
        from htn.jshop.language import syntax as S
        from htn.jshop.language.terms import source_atom

        if self.dispatcher is None:
            tasks = S.task_atoms(self.inputs.instance.tasks)
        else:
            d = self.dispatcher
            tasks = S.task_atoms(pending_tasks(d.root, d.tree_known, d.instance.tasks))
        return [source_atom(t.name, t.args) for t in tasks]

    def interrupted(self, why: str = "") -> RunResult:
        """End the run as interrupted now (outside :meth:`execute`): the robot
        holds its pose, the log gets the ``interrupted`` event and the summary."""
        assert self.dispatcher is not None, "the run has not begun"
        return self._result(self.dispatcher.interrupted(why))

    def _result(self, summary: RunSummary) -> RunResult:
        assert self.log is not None and self.dispatcher is not None  # begun
        return RunResult(summary, self.log.events, self.dispatcher.plan_lines(), self.notes)

    def believed(self) -> list[BelievedFact]:
        """The facts the run believes now, ``(pred, args)`` pairs: the
        initial state with every verified step's effects (and, after a
        repair, what was observed); the problem's state before it begins."""
        if self.dispatcher is None:
            return [(a.pred, a.args) for a in self.inputs.instance.state]
        return list(self.dispatcher.belief.state.facts())

    def end_now(self, why: str) -> None:
        """End the log now, from another thread (a watchdog that ends the
        process because user code kept running after a stop): its
        ``interrupted`` event and summary, whatever the dispatcher is doing."""
        log = self.log
        if log is None or log.ended:
            return
        try:
            self.interrupted(why)
        except BaseException:  # noqa: BLE001 - the dispatcher is mid-tick: end the log itself
            log.emit(None, None, "interrupted", None, "ended by the watchdog")
            log.emit(None, None, "summary", None, "interrupted", result="interrupted")
        log.close()

    def fail(self, exc: BaseException) -> None:
        """End the log with an ``error`` summary: ``exc`` stopped the run."""
        if self.log is not None and not self._closed:
            self.log.emit(
                None, None, "summary", None, f"error: {type(exc).__name__}: {exc}", result="error"
            )

    def close(self) -> None:
        """Close the log and (if it was built here) the robot."""
        if self._closed:
            return
        self._closed = True
        if self.log is not None:
            self.log.close()
        if self.owned:
            self.robot.close()

    def __enter__(self) -> Execution:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if exc is not None:
            self.fail(exc)
        self.close()
