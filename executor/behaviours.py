"""The action state machine as a py_trees subtree, one per plan step.

As PlanSys2 builds one small behaviour tree per action, every operator
instance becomes this subtree (the paper's execute -> monitor -> report,
section 4, with the hold-monitors running beside execute)::

    Report  "(!move_base jenny counter_front sofa_front)"  outcome to the dispatcher;
      RetryAborted  "retry <= 2"                          a one-shot: done once verified
        Sequence  "attempt"                               (retrying is emitted here)
          Parallel  "execute | hold"                      succeeds when execute does
            Execute  "execute"                            ticks the robot skill
            Hold  "no collision"                          one per hold-monitor
            Hold  "what it carries stays in the gripper"
          Monitor  "monitor"                              verified / aborted

Each behaviour keeps py_trees' life cycle (``initialise`` / ``update`` /
``terminate``): ``Execute`` starts the skill in ``initialise``, advances it by
the robot's ``steps_per_tick`` physics steps in each ``update``, and closes it
in ``terminate`` when preempted. A ``Hold`` that fails makes the parallel
fail, which preempts the skill at once: the attempt is ``aborted`` at that
tick's simulated time and, since retrying cannot restore what broke, not
retried. What the behaviours of one action share (step, machine, attempt,
outcome) is an :class:`ActionContext`, as SMACH states share userdata.
Display lives elsewhere (``htn.cli.tree_view``).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Generator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, cast

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import OneShotPolicy, ParallelPolicy, Status

from htn.jshop.language.errors import HtnError
from htn.robot.interface import Check, Robot, SkillResult

from .outcome import Outcome

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Step
    from htn.jshop.plans.tree import TaskTree

    from .machines.base import ActionMachine, HoldMonitor


class Executor(Protocol):
    """What an action's behaviours see of the task dispatcher: the robot,
    the event log, and the reports the paper's state machines send it. They
    report through these methods and never write its fields."""

    robot: Robot

    def emit(self, ctx: ActionContext, event: str, detail: str = "", **extra: Any) -> None: ...

    def begun(self, ctx: ActionContext, first: bool) -> None:
        """``ctx``'s action runs now (``first``: its first attempt)."""

    def retrying(self, ctx: ActionContext) -> None:
        """``ctx``'s action was aborted and is tried again."""

    def report(self, ctx: ActionContext, ok: bool) -> None: ...

    def apply_internal(self, step: Step) -> bool: ...


@dataclass
class ActionContext:
    """One plan step being executed: what its behaviours share."""

    step: Step  # the plan Step
    machine: ActionMachine | None  # its ActionMachine (None for internal steps)
    limit: int  # retries allowed after an aborted attempt
    node: TaskTree | None = None  # its task-tree node (path), if known
    attempt: int = 0
    outcome: Outcome | None = None
    preempted: bool = False
    done: bool = False  # verified: never run again
    number: int | None = None  # its 1-based step, once verified
    detail: str = ""
    holds: list[str] = field(default_factory=list)
    text: str = ""  # the step as the plan shows it

    def __post_init__(self) -> None:
        self.text = str(self.step)


class ActionBehaviour(py_trees.behaviour.Behaviour):
    """A behaviour of one action's subtree: it knows its context and the executor."""

    def __init__(self, name: str, ctx: ActionContext, executor: Executor):
        super().__init__(name)
        self.ctx, self.executor = ctx, executor

    def emit(self, event: str, detail: str = "", **extra: Any) -> None:
        self.executor.emit(self.ctx, event, detail, **extra)


class Execute(ActionBehaviour):
    """Execute the action: start the robot skill, tick it to its end."""

    ticking: Generator[None, None, SkillResult] | None  # the skill in progress
    result: SkillResult | None  # the skill's result, once it has ended

    def initialise(self) -> None:
        ctx = self.ctx
        ctx.attempt += 1
        ctx.outcome, ctx.preempted = None, False
        self.executor.begun(ctx, ctx.attempt == 1)
        self.emit("start")
        self.ticking, self.result = None, None
        assert ctx.machine is not None  # a step without a machine is Unavailable
        try:
            started = ctx.machine.execute(self.executor.robot, *ctx.step.args)
        except TypeError as exc:  # wrong number of parameters in the plan step
            started = SkillResult(False, f"bad parameters: {exc}")
        except HtnError as exc:
            started = SkillResult(False, exc.message)
        if inspect.isgenerator(started):  # a skill's generator (htn.robot.interface.Ticking)
            self.ticking = cast("Generator[None, None, SkillResult]", started)
        else:
            self.result = cast(SkillResult, started)

    def update(self) -> Status:
        if self.ticking is not None:
            try:
                for _ in range(self.executor.robot.steps_per_tick):
                    next(self.ticking)
                return Status.RUNNING
            except StopIteration as stop:
                self.ticking, self.result = None, stop.value
            except HtnError as exc:
                self.ticking, self.result = None, SkillResult(False, exc.message)
        result = self.result
        assert result is not None  # set by initialise, or when the skill ended
        if result.ok:
            self.emit("feedback", result.detail)
            self.emit(Outcome.FINISHED.value, result.detail)
            return Status.SUCCESS
        self.ctx.outcome = Outcome.FAILED
        self.emit(Outcome.FAILED.value, result.detail)
        return Status.FAILURE

    def terminate(self, new_status: Status) -> None:
        if self.ticking is not None:  # preempted (a hold-monitor, or a halt)
            self.ticking.close()
            self.ticking = None
            self.executor.robot.hold()


class Hold(ActionBehaviour):
    """A hold-monitor: RUNNING while its condition holds, FAILURE (the
    action aborted, preempted) the first tick it does not."""

    def __init__(
        self, name: str, ctx: ActionContext, executor: Executor, check: Callable[[], Check]
    ):
        super().__init__(name, ctx, executor)
        self.check = check

    def update(self) -> Status:
        seen = self.check()
        if seen.ok:
            return Status.RUNNING
        self.ctx.outcome, self.ctx.preempted = Outcome.ABORTED, True
        self.emit(
            Outcome.ABORTED.value, f"{self.name} no longer holds: {seen.detail}", hold=self.name
        )
        return Status.FAILURE


class Monitor(ActionBehaviour):
    """The monitoring action: did the world show the expected effect?"""

    def update(self) -> Status:
        ctx = self.ctx
        assert ctx.machine is not None  # a step without a machine is Unavailable
        seen = ctx.machine.monitor(self.executor.robot, *ctx.step.args)
        ctx.outcome = Outcome.VERIFIED if seen.ok else Outcome.ABORTED
        detail = (
            seen.detail if seen.ok or retries_left(ctx) else f"{seen.detail}; {out_of_retries(ctx)}"
        )
        self.emit(ctx.outcome.value, detail)
        return Status.SUCCESS if seen.ok else Status.FAILURE


def retries_left(ctx: ActionContext) -> bool:
    """May the action be tried again? ``limit`` retries after the first
    attempt, however they came (its retry decorator, or repair)."""
    return ctx.attempt <= ctx.limit


def out_of_retries(ctx: ActionContext) -> str:
    """What an action whose retries are used up could have had, in the
    command line's words: ``1 retry used up (--retries hand=2 allows one more)``."""
    name = ctx.step.name.lstrip("!")
    if ctx.limit == 0:
        return f"no retries for {ctx.step.name} (--retries {name}=1 allows one)"
    used = f"{ctx.limit} retr{'y' if ctx.limit == 1 else 'ies'}"
    return f"{used} used up (--retries {name}={ctx.limit + 1} allows one more)"


class RetryAborted(py_trees.decorators.Retry):
    """Retry an attempt the monitor did not verify, up to the operator's
    limit (counted over the action's attempts, so a retry that repair made
    counts too); a failed attempt (internal error) or a preempted one is
    final here (repair may retry it, see the task dispatcher)."""

    def __init__(self, child: Behaviour, ctx: ActionContext, executor: Executor):
        super().__init__(f"retry <= {ctx.limit}", child, ctx.limit + 1)
        self.ctx, self.executor = ctx, executor

    def update(self) -> Status:
        ctx = self.ctx
        if self.decorated.status != Status.FAILURE:
            return self.decorated.status
        if ctx.outcome is Outcome.ABORTED and not ctx.preempted and retries_left(ctx):
            self.failures += 1
            self.executor.retrying(ctx)
            return Status.RUNNING
        return Status.FAILURE


class Report(py_trees.decorators.OneShot):
    """The paper's status report: the action's final outcome goes to the task
    dispatcher (which updates its belief state and the plan's progress).
    Once verified, the action is done: py_trees' one-shot, which a repaired
    tree ticks again, returns success without running it again."""

    def __init__(self, child: Behaviour, ctx: ActionContext, executor: Executor):
        super().__init__(ctx.text, child, OneShotPolicy.ON_SUCCESSFUL_COMPLETION)
        self.ctx, self.executor = ctx, executor

    def update(self) -> Status:
        if self.final_status:
            return self.final_status
        status = self.decorated.status
        if status != Status.RUNNING:
            self.executor.report(self.ctx, status == Status.SUCCESS)
        return status


class ApplyInternal(ActionBehaviour):
    """An internal operator (``!!``): applied to the belief state only (once)."""

    def update(self) -> Status:
        ctx = self.ctx
        if ctx.done:
            return Status.SUCCESS
        self.executor.begun(ctx, True)
        ok = self.executor.apply_internal(ctx.step)
        ctx.attempt, ctx.outcome = 1, Outcome.VERIFIED if ok else Outcome.FAILED
        self.emit(
            ctx.outcome.value,
            "internal operator applied to the belief state"
            if ok
            else "internal operator not applicable",
        )
        self.executor.report(ctx, ok)
        return Status.SUCCESS if ok else Status.FAILURE


class Unavailable(ActionBehaviour):
    """A step no action state machine is registered for: it fails."""

    def update(self) -> Status:
        self.executor.begun(self.ctx, True)
        self.ctx.attempt, self.ctx.outcome = 1, Outcome.FAILED
        self.emit(
            Outcome.FAILED.value, f"no action state machine is registered for {self.ctx.step.name}"
        )
        self.executor.report(self.ctx, False)
        return Status.FAILURE


def action_subtree(
    ctx: ActionContext, executor: Executor, holds: list[HoldMonitor]
) -> py_trees.behaviour.Behaviour:
    """The behaviour tree of one plan step (see the module docstring). On a
    robot whose skills are instantaneous there is nothing to watch while they
    run: execute stands alone, without the parallel and hold-monitors."""
    top: Behaviour
    if ctx.step.internal:
        top = ApplyInternal(ctx.text, ctx, executor)
    elif ctx.machine is None:
        top = Unavailable(ctx.text, ctx, executor)
    else:
        execute: Behaviour = Execute("execute", ctx, executor)
        if holds:
            ctx.holds = [label for label, _ in holds]
            execute = py_trees.composites.Parallel(
                "execute | hold",
                ParallelPolicy.SuccessOnSelected([execute]),
                children=[execute, *(Hold(label, ctx, executor, fn) for label, fn in holds)],
            )
        attempt = py_trees.composites.Sequence(
            "attempt", memory=True, children=[execute, Monitor("monitor", ctx, executor)]
        )
        top = Report(RetryAborted(attempt, ctx, executor), ctx, executor)
    # an attribute of our own on py_trees' behaviour, which does not declare it
    setattr(top, "htn_action", ctx)  # noqa: B010
    return top
