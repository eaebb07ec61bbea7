"""A planner and executor that lives across goals: the use case under a
robot node (issue 36), with no middleware in it.

An :class:`Agent` holds a :class:`~htn.api.world.WorldModel` and one robot
for its whole life. Each goal (a task list) is planned from what the world
model believes now, run with the same executor, monitors, retries and
repair as ``htn run``, and what the run verified becomes the world model.
A goal ends in one of five outcomes:

* ``verified``, ``failed``, ``aborted``: as ``htn run``;
* ``preempted``: :meth:`Agent.preempt` halted it (a cancel, or a newer
  goal), while it ran or was being planned: the running action's skill is
  stopped and the robot holds its pose; the steps verified so far stay in
  the world model; the log's summary says ``preempted`` and why, and
  :attr:`GoalResult.remaining` holds the tasks it did not complete;
* ``refused``: the goal could not be planned (a located error in its text,
  or no plan from the current state); nothing moved.

A newer goal that preempts a goal (``preempt(why, next_goal=tasks)``) is
planned from what the running goal believes at that moment; where its plan
starts with the very action that runs now (the same ground step), that
action goes on instead of being cancelled and started again: the running
goal halts when it ends (before its next action), and the newer goal's run
(:meth:`execute` of the same tasks) takes it as its first step, verified.

A preempted goal can be resumed (:meth:`resume`) after the goal that
preempted it: the top-level tasks of its task list that it did not complete
are planned again from the world model (what was verified meanwhile; a task
partially executed is planned whole, from the state it was left in) and run;
its steps verified before stay done.

One goal runs at a time; :meth:`execute` and :meth:`resume` are meant to be
called from one thread, :meth:`preempt` and :meth:`plan` from any.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import Guard

from .world import WorldModel, plan_goal

if TYPE_CHECKING:
    from htn.executor.behaviours import ActionContext
    from htn.jshop.language import syntax as S
    from htn.jshop.plans.plan import Plan
    from htn.robot.interface import Robot

    from .inputs import DomainInput, FunctionsInput, ProblemInput, StrPath
    from .run import Execution, RunResult
    from .run_inputs import RetriesInput
    from .world import Fact

PREEMPTED = "preempted by a newer goal or a cancel"


@dataclass
class GoalResult:
    """How a goal ended (the fields of ``ExecuteTasks``' result)."""

    outcome: str  # verified | failed | aborted | preempted | refused
    summary: str = ""  # the line htn run prints
    error: str = ""  # the located error, when refused
    plan: list[str] = field(default_factory=list)  # the steps, as executed
    tree: str = ""  # the plan's task tree, JSON
    steps: int = 0
    verified: int = 0
    log: list[dict[str, Any]] = field(default_factory=list)  # every event, as logged
    remaining: str = ""  # preempted: the top-level tasks not completed, a task list
    tasks: str = ""  # the goal's task list, as given
    retries: int = 0
    replans: int = 0
    resumed: int = 0  # how often it was resumed after a preemption

    @property
    def ok(self) -> bool:
        return self.outcome == "verified"

    @property
    def done(self) -> list[str]:
        """The steps verified (the first ``verified`` of ``plan``)."""
        return self.plan[: self.verified]


@dataclass
class _Handover:
    """A newer goal whose plan starts with the action running now: that
    action goes on, and the goal's run takes it as verified."""

    tasks: str
    plan: Plan
    problem: S.Problem
    execution: Execution  # the run it goes on from
    ctx: ActionContext  # the action that goes on

    def went_on(self) -> bool:
        """Was that action the last one its run verified?"""
        return self.execution.last_verified() is self.ctx


class Agent:
    """Plans and runs goals on one robot, keeping a world model between them.

    ``domain``, ``problem`` (the first state; optional), ``functions``: as
    :class:`~htn.api.world.WorldModel`. ``robot``: a back end's name (built
    once, for the problem's world) or a :class:`~htn.robot.interface.Robot`.
    ``faults``, ``seed``, ``retries``, ``replan``: as :func:`htn.api.run.run`,
    for every goal. ``stops``: the process's :class:`htn.process.Stops`."""

    def __init__(
        self,
        domain: DomainInput,
        problem: ProblemInput | None = None,
        *,
        robot: str | Robot = "symbolic",
        functions: FunctionsInput = None,
        faults: str = "",
        seed: int = 0,
        retries: RetriesInput = None,
        replan: bool = False,
        stops: Guard | None = None,
    ) -> None:
        self.world = WorldModel(domain, problem, functions, stops)
        self.retries, self.replan, self.stops = retries, replan, stops
        self.robot_name = robot if isinstance(robot, str) else type(robot).__name__
        self.robot: Robot = self._robot(robot, faults, seed) if isinstance(robot, str) else robot
        self._busy = False  # a goal is being planned or run
        self._running: Execution | None = None  # the Execution of the goal being run
        self._preempted: str | None = None
        self._handover: _Handover | None = None
        self._lock = threading.Lock()
        _warm_up()

    def _robot(self, name: str, faults: str, seed: int) -> Robot:
        from htn.robot.backends import RobotRequest, make_robot

        from .extras import require_robot_extra

        require_robot_extra(name, f"the {name} robot")
        problem = self.world.problem("()", "world")  # the world as believed, no tasks
        robot: Robot = make_robot(
            name,
            RobotRequest(
                self.world.domain, problem.instances[0], faults, seed, False, self.world.functions
            ),
        )
        return robot

    # ------------------------------------------------------------ goals
    def plan(self, tasks: str, source: str = "goal") -> Plan | None:
        """The first plan of ``tasks`` from the current world model, or None
        if there is none (an :class:`HtnError` for a bad goal)."""
        return self._first_plan(tasks, source)[0]

    def _first_plan(
        self, tasks: str, source: str, facts: Iterable[Fact] | None = None
    ) -> tuple[Plan | None, S.Problem]:
        """(the first plan or None, the goal's problem it was planned in):
        the goal read once, so the run checks the plan in the very state it
        was made from, whatever facts arrive meanwhile. ``facts``: plan from
        these ``(pred, args)`` pairs, not from the world model."""
        if facts is None:
            stream = plan_goal(self.world, tasks, source=source, stops=self.stops)
        else:
            from htn.jshop.language import syntax as S

            from .plan import plan

            problem = self.world.problem(tasks, source)
            problem.instances[0].state = [S.Atom(p, tuple(args)) for p, args in facts]
            stream = plan(
                self.world.domain, problem, functions=self.world.functions, stops=self.stops
            )
        try:
            return next(iter(stream), None), stream.problem
        finally:
            stream.close()

    def execute(
        self,
        tasks: str,
        *,
        source: str = "goal",
        log: StrPath | None = None,
        on_event: Callable[[dict[str, Any]], None] | None = None,
    ) -> GoalResult:
        """Plan ``tasks`` from the world model and run the plan on the robot;
        ``on_event`` gets every event as it is logged (and ``log``, a path,
        the JSON Lines log of ``htn run``). Where the goal preempted the one
        before with ``preempt(next_goal=tasks)`` and the action that went on
        was verified, the plan made then is run, that action as its first
        step, verified (the log says ``adopted``)."""
        return self._run(tasks, source, log, on_event)

    def resume(
        self,
        result: GoalResult,
        *,
        log: StrPath | None = None,
        on_event: Callable[[dict[str, Any]], None] | None = None,
    ) -> GoalResult:
        """Go on with the preempted goal ``result``: plan its remaining
        tasks (:attr:`GoalResult.remaining`) from the world model and run
        them. The result is the whole goal's: its plan is the steps verified
        before and the new plan's, its counts and summary line are the
        goal's (the line says it was resumed), and the log's summary event
        says ``resumed`` (the tasks, how many steps were verified before).
        A state the domain has no plan for ends it ``refused``, saying so;
        preempted again, it can be resumed again."""
        if not result.remaining:
            raise ValueError(f"a {result.outcome} goal with no tasks left has nothing to resume")
        return self._run(result.remaining, "goal", log, on_event, result)

    def _run(
        self,
        tasks: str,
        source: str,
        log: StrPath | None,
        on_event: Callable[[dict[str, Any]], None] | None,
        before: GoalResult | None = None,
    ) -> GoalResult:
        from .run import prepare

        with self._lock:
            self._busy, self._preempted = True, None
            handover, self._handover = self._handover, None
        try:
            adopted: str | None = None
            since = self.world.mark()  # facts reported from now on outlive the run
            plan: Plan | None
            try:
                if (
                    before is None
                    and handover is not None
                    and handover.tasks == tasks
                    and handover.went_on()
                ):
                    plan, problem, adopted = handover.plan, handover.problem, handover.ctx.text
                else:
                    self._observe()
                    plan, problem = self._first_plan(tasks, source)
                if plan is None:
                    raise HtnError(
                        "no plan reaches the goal from the current state"
                        if before is None
                        else f"resuming {tasks}: no plan reaches these tasks "
                        "from the current state",
                        source,
                    )
                # a log that cannot be written (a folder gone) refuses the goal too
                execution = prepare(
                    plan,
                    robot=self.robot,
                    domain=self.world.domain,
                    problem=problem,
                    retries=self.retries,
                    replan=self.replan,
                    log=log,
                    on_event=on_event,
                    stops=self.stops,
                )
            except HtnError as exc:
                return self._refused(exc, tasks, before)
            if adopted:
                execution.adopt(1, "went on from the goal it preempted, and was verified there")
            if before is not None:
                execution.annotate(
                    resumed={
                        "tasks": tasks,
                        "times": before.resumed + 1,
                        "verified_before": before.verified,
                        "goal": before.tasks or tasks,
                    }
                )
            with self._lock:
                self._running = execution
                if self._preempted is not None:  # while it was being planned
                    execution.halt(self._preempted, "preempted")
            with execution:
                execution.begin()
                try:
                    result = execution.execute()
                except KeyboardInterrupt as exc:  # outside the ticks: the log ends in order
                    result = execution.interrupted(str(exc))
                self.world.believe(execution.believed(), since)
            remaining = ""
            if result.result == "preempted":
                remaining = "(" + " ".join(execution.pending_tasks()) + ")"
        finally:
            with self._lock:
                self._running, self._busy = None, False
        return self._result(plan, result, tasks, remaining, before)

    def _observe(self) -> None:
        """A robot that observes the world itself (``observes_world``: a
        robot in another process, which may have been restarted or moved
        meanwhile) is asked what it sees before a goal is planned; its
        observation replaces the believed facts of the dynamic predicates."""
        if getattr(self.robot, "observes_world", False):
            facts = self.robot.observe()
            if facts:
                self.world.observed(facts)

    def preempt(self, why: str = PREEMPTED, *, next_goal: str | None = None) -> bool:
        """Halt the goal being run at its current action (the robot holds
        its pose), or the goal being planned before its first step; it ends
        ``preempted`` (the log's summary too, with ``why``). False if no
        goal is being planned or run.

        ``next_goal``: the task list of the goal that preempts it (run next
        with :meth:`execute`). It is planned now from what the running goal
        believes; if that plan starts with the action running now, the
        action goes on to its end and the goal halts before its next action
        (ending as it would if that action was its last, or failed); the
        next goal's run then takes that action as its verified first step.
        Otherwise (or if the next goal has no plan) the goal halts now."""
        keep = self._keep(next_goal) if next_goal else None
        with self._lock:
            if not self._busy:
                return False
            self._preempted = why
            run = self._running
            if run is not None:
                if keep is not None and keep.execution is run:
                    self._handover = keep
                    run.halt(why, "preempted", after=keep.ctx)
                else:
                    run.halt(why, "preempted")
            return True

    def _keep(self, tasks: str) -> _Handover | None:
        """The handover of the action running now to the goal ``tasks``,
        if its plan from the running goal's belief starts with that action."""
        with self._lock:
            run = self._running
        now = run.running_action() if run is not None else None
        if run is None or now is None:
            return None
        ctx, facts = now
        try:
            plan, problem = self._first_plan(tasks, "goal", facts)
        except HtnError:
            return None
        if plan is None or not plan.steps or str(plan.steps[0]) != ctx.text:
            return None
        return _Handover(tasks, plan, problem, run, ctx)

    def _refused(self, exc: HtnError, tasks: str, before: GoalResult | None) -> GoalResult:
        if before is None:
            return GoalResult("refused", f"refused: {exc.message}", error=str(exc), tasks=tasks)
        return replace(
            before,
            outcome="refused",
            summary=f"refused: {exc.message}",
            error=str(exc),
            plan=before.done,
            steps=before.verified,
            log=[],
            remaining="",
        )

    def _result(
        self,
        plan: Plan,
        result: RunResult,
        tasks: str,
        remaining: str,
        before: GoalResult | None,
    ) -> GoalResult:
        s = result.summary
        tree = json.dumps(plan.tree.to_dict()) if plan.tree is not None else ""
        if before is None:
            return GoalResult(
                s.result,
                s.line(),
                plan=list(result.plan),
                tree=tree,
                steps=s.steps,
                verified=s.verified,
                log=list(result.events),
                remaining=remaining,
                tasks=tasks,
                retries=s.retries,
                replans=s.replans,
            )
        # resumed: the goal's counts, the steps verified before it included
        k = before.verified
        whole = replace(
            s,
            steps=s.steps + k,
            verified=s.verified + k,
            retries=s.retries + before.retries,
            replans=s.replans + before.replans,
            executed=s.executed + k,
            failed_at=None if s.failed_at is None else s.failed_at + k,
        )
        times = before.resumed + 1
        line = (
            f"{whole.line()}; resumed{'' if times == 1 else f' {times} times'} after a "
            f"preemption, {k} step{'' if k == 1 else 's'} verified before"
        )
        return GoalResult(
            s.result,
            line,
            plan=before.done + list(result.plan),
            tree=tree,
            steps=whole.steps,
            verified=whole.verified,
            log=list(result.events),
            remaining=remaining,
            tasks=before.tasks,
            retries=whole.retries,
            replans=whole.replans,
            resumed=times,
        )


def _warm_up() -> None:
    """Load now what the first goal would load (the executor, py_trees, the
    action machines and their plugins, about 0.1 s), so that a goal's first
    action starts as soon after its plan as every later goal's."""
    from htn.executor.machines.base import load_plugins

    from . import run  # noqa: F401  (the executor and py_trees)

    load_plugins()
