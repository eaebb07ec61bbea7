"""Task dispatcher (the paper's task management, section 4), on a behaviour tree.

The plan's task tree becomes a py_trees behaviour tree of the same shape
(:mod:`htn.executor.task_bt`): compound tasks are sequences, each operator is
its action state machine's subtree (:mod:`htn.executor.behaviours`). The
**task dispatcher** ticks the tree; each tick advances the running robot
skill by a few physics steps and runs the action's hold-monitors. The
outcome of every action is reported back to the dispatcher, which keeps the
belief state (the verified effects) and the plan's progress. Internal
operators (``!!``) are applied to the belief state only.

When an action ends failed or aborted, the robot stops and holds its pose (as
in the paper). With ``replan=True`` the dispatcher repairs instead and goes
on: first by trying the step again, if its retry limit allows and it still
applies in the observed state, else by re-planning in the task tree
(:mod:`htn.executor.repair`). :meth:`TaskDispatcher.halt`
(Ctrl-C, SIGTERM) stops the tree between two ticks, and the run ends
``interrupted``; a program that halts it for another goal (a robot node's
newer goal, or a cancel) says so, and the run ends ``preempted``. Such a
halt may let the running action go on to its end (``after``): the run then
halts before the next action begins.

Events go to an :class:`~htn.executor.log.EventLog`; ``step`` is the action's
1-based position in the plan as executed (steps verified before it, plus
one). Each fault the robot injects becomes a ``fault`` event as it happens.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterable, Sequence
from typing import TYPE_CHECKING, Any

import py_trees
from py_trees.behaviour import Behaviour
from py_trees.common import Status

from htn.jshop.language import syntax as S
from htn.jshop.search.planner import Planner

from .behaviours import ActionContext, action_subtree, out_of_retries, retries_left
from .log import EventLog
from .machines import HoldMonitor, all_of, machine_for
from .machines.base import carry_predicate
from .outcome import Outcome
from .repair import find_repair, graft, observed_instance, retry_applies
from .summary import RunSummary as RunSummary  # re-exported: the run's summary
from .task_bt import action_of, actions, build, flat_tree, task_node
from .tree_events import NodeNumbers, tree_detail, tree_nodes

if TYPE_CHECKING:
    from htn.jshop.language.functions import FunctionTable
    from htn.jshop.plans.plan import Step
    from htn.jshop.plans.tree import TaskTree
    from htn.robot.interface import Check, Robot

STOPPED_BY_USER = "stopped by the user"  # why a run halted, unless told otherwise
INTERRUPTED, PREEMPTED = "interrupted", "preempted"  # what a halted run's summary says


class Halted(KeyboardInterrupt):
    """Raised when the next action would start after a halt: the run ends
    as after an interrupt between two ticks (its message is the halt's reason)."""


class TaskDispatcher:
    """Ticks the behaviour tree of a plan on a robot, repairing it on request.

    ``tree`` is the plan's task tree (``Plan.tree``; its leaves index
    ``steps``); without it the plan runs as one sequence of actions.
    """

    def __init__(
        self,
        robot: Robot,
        domain: S.Domain,
        instance: S.ProblemInstance,
        steps: Iterable[Step],
        retries: dict[str, int],
        log: EventLog,
        replan: bool = False,
        functions: FunctionTable | None = None,
        max_replans: int = 10,
        tree: TaskTree | None = None,
    ):
        self.robot = robot
        self.domain = domain
        self.instance = instance
        self.limits = retries
        self.log = log
        self.replan = replan
        self.functions = functions
        self.max_replans = max_replans
        self.tree_known = tree is not None
        self.belief = Planner.for_state(domain, instance.state, functions)
        self.done: list[ActionContext] = []  # verified steps, in order
        self.failed: ActionContext | None = None
        self.running: ActionContext | None = None
        self.retries = self.replans = self.started = 0
        self._faults_seen = 0
        self._halt: str | None = None
        self._halt_as = INTERRUPTED  # what the summary of a halted run says
        self._halt_later: tuple[str, str] | None = None  # (why, as): at the next action
        # running and the belief, as another thread sees them; reentrant, since a
        # signal handler's halt() may run in the thread that holds it (the long
        # fuzz run of issue 34 met htn run's deadline while report() held it)
        self._lock = threading.RLock()
        self._in_tick = False
        self.summary_extra: dict[str, Any] = {}  # more fields for the summary event
        # (action, attempt) -> what it carries
        self._carrying: tuple[tuple[int, int] | None, list[str]] = (None, [])
        self.carry = carry_predicate(domain.name)  # the domain's word for carrying
        self.carry_checks = self.carry is not None and "still_held" in robot.check_names()
        steps = list(steps)
        tree = tree if tree is not None else flat_tree(steps)
        self.root = build(tree, steps, self._action)
        self.nodes = NodeNumbers()  # the task-tree nodes as the log numbers them
        self.tick_listeners: list[Callable[[], object]] = []  # between ticks (a camera view)
        self._log_tree([tree], None, _plan_step)

    # ------------------------------------------------------------ building
    def _action(self, step: Step, node: TaskTree) -> Behaviour:
        machine = None if step.internal else machine_for(step.name, self.domain.name, self.robot)
        ctx = ActionContext(step, machine, self.limits.get(step.name, 0), node)
        holds: list[HoldMonitor] = []
        if machine is not None and not self.robot.instantaneous:
            holds = machine.holds(self.robot, *step.args)
            if self.carry_checks:
                holds = [
                    *holds,
                    ("what it carries stays in the gripper", lambda: self._carried_in_gripper(ctx)),
                ]
        return action_subtree(ctx, self, holds)

    # ------------------------------------------------------------ what the behaviours call
    def number(self, ctx: ActionContext) -> int:
        return ctx.number or len(self.done) + 1

    def emit(self, ctx: ActionContext | None, event: str, detail: str = "", **extra: Any) -> None:
        self._flush_faults()
        if ctx is not None:
            extra = {"node": self.nodes.of(ctx.node), **extra}
        self.log.emit(
            self.number(ctx) if ctx else None,
            ctx.text if ctx else None,
            event,
            ctx.attempt if ctx else None,
            detail,
            **extra,
        )

    def _log_tree(
        self,
        tops: Iterable[TaskTree],
        parent: int | None,
        step_of: Callable[[TaskTree], int | None],
        replaces: Sequence[int | None] = (),
    ) -> None:
        """A ``tree`` event with the nodes of the subtrees ``tops``, each
        under ``parent`` (see :mod:`htn.executor.tree_events`)."""
        ctxs = {id(a.node): a for a in actions(self.root)}
        nodes = [
            n
            for top in tops
            for n in tree_nodes(top, self.nodes, parent, step_of, lambda n: ctxs.get(id(n)))
        ]
        self.log.emit(
            None,
            None,
            "tree",
            None,
            tree_detail(nodes, len(replaces)),
            nodes=nodes,
            parent=parent,
            replaces=list(replaces),
        )

    def begun(self, ctx: ActionContext, first: bool) -> None:
        """An action's behaviours say it runs now (``first``: its first
        attempt, which counts it as started). A halted run starts no further
        action, even within the tick that was running when it was halted
        (the symbolic robot's actions all end in one tick): :class:`Halted`
        ends the tick, and :meth:`run` ends the run as interrupted (or preempted)."""
        with self._lock:
            if self._halt_later is not None and not self._halt:
                (self._halt, self._halt_as), self._halt_later = self._halt_later, None
            if self._halt:
                raise Halted(self._halt)
            self.running = ctx
        self.started += first

    def retrying(self, ctx: ActionContext) -> None:
        """An aborted action is tried again (its retry limit allows it)."""
        self.retries += 1
        self.emit(ctx, Outcome.RETRYING.value, f"retry {ctx.attempt} of {ctx.limit}")

    def report(self, ctx: ActionContext, ok: bool) -> None:
        """The final outcome of an action (the paper's status report)."""
        if ok:
            with self._lock:
                if not ctx.step.internal:
                    self.belief.apply_step(ctx.step.name, tuple(ctx.step.args))
                ctx.done = True
                self.done.append(ctx)
                ctx.number = len(self.done)
        else:
            self.failed = ctx

    def adopt(self, count: int, detail: str) -> None:
        """The first ``count`` steps of the plan were executed and verified
        before this run began (an action that went on from a preempted
        run): each is logged ``verified`` with ``detail`` (and
        ``adopted``), applied to the belief state and never run here."""
        for top in [b for b in self.root.iterate() if hasattr(b, "htn_action")][:count]:
            ctx = action_of(top)
            assert ctx is not None
            ctx.attempt, ctx.outcome = 1, Outcome.VERIFIED
            self.started += 1
            self.report(ctx, True)
            if isinstance(top, py_trees.decorators.OneShot):
                top.final_status = Status.SUCCESS  # it bounces: success, not run
            self.emit(ctx, Outcome.VERIFIED.value, detail, adopted=True)

    def running_action(self) -> tuple[ActionContext, list[tuple[str, tuple[Any, ...]]]] | None:
        """``(its context, the belief state's facts as it began)`` of the
        action running now, or None (between actions, an internal step, an
        action that has ended, a halted run): what another thread needs to
        decide whether a new plan may go on from it (safe from any thread)."""
        with self._lock:
            ctx = self.running
            if (
                ctx is None
                or ctx.done
                or ctx.outcome is not None
                or ctx.step.internal
                or self._halt
                or self._halt_later
            ):
                return None
            return ctx, list(self.belief.state.facts())

    def apply_internal(self, step: Step) -> bool:
        with self._lock:
            ok = self.belief.apply_step(step.name, tuple(step.args))
        if ok:
            self.robot.apply_internal(step.name, tuple(step.args))
        return ok

    def carried(self, ctx: ActionContext) -> list[str]:
        """What the belief state says the robot carries (``(P ... ?obj)`` for
        the domain's carry predicate P), except what this step lets go of."""
        held = [args[-1] for pred, args in self.belief.state.facts() if pred == self.carry]
        if not held:
            return []
        released: set[str] = set()
        for op, env in self.belief.step_options(ctx.step.name, tuple(ctx.step.args)):
            deleted, _ = self.belief.effects(op, env)
            released |= {args[-1] for pred, args in deleted if pred == self.carry}
            break
        return [o for o in held if o not in released]

    def _carried_in_gripper(self, ctx: ActionContext) -> Check:
        from htn.robot.interface import Check

        if self._carrying[0] != (id(ctx), ctx.attempt):  # the belief is fixed while it runs
            self._carrying = ((id(ctx), ctx.attempt), self.carried(ctx))
        objs = self._carrying[1]
        if not objs:
            return Check(True, "carries nothing")
        return all_of(*(self.robot.check("still_held", o) for o in objs))

    def _flush_faults(self) -> None:
        """A ``fault`` event for each fault the robot injected since the last call."""
        for f in self.robot.injected_faults()[self._faults_seen :]:
            self._faults_seen += 1
            ctx = self.running
            where = {"node": self.nodes.of(ctx.node)} if ctx else {}
            self.log.emit(
                self.number(ctx) if ctx else None,
                ctx.text if ctx else None,
                "fault",
                None,
                f["detail"],
                kind=f["kind"],
                sim_t=f["sim_t"],
                **where,
            )

    # ------------------------------------------------------------ the tick loop
    def halt(
        self, why: str = "", outcome: str = INTERRUPTED, after: ActionContext | None = None
    ) -> bool:
        """Stop the tree before its next tick (safe from a signal handler or
        another thread); ``why`` is logged with the ``interrupted`` event
        and in the summary, whose result is ``outcome`` (``interrupted``;
        ``preempted`` when a program halts it for another goal). ``after``:
        an action's context: while that action runs, it goes on to its end
        (verified, or failed, or repaired as usual) and the run halts before
        the next action begins (or ends as it would, if none is left); if it
        is no longer running, the run halts now.
        True while a tick runs: the halt takes effect when it ends. Else
        False: a signal handler raises its interrupt too, which :meth:`run`
        ends the same way (between two ticks, e.g. while repair plans)."""
        why = why or STOPPED_BY_USER
        with self._lock:
            if (
                after is not None
                and not self._halt
                and self.running is after
                and not after.done
                and after.outcome is None
            ):
                self._halt_later = (why, outcome)
            else:
                self._halt, self._halt_as = why, outcome
        return self._in_tick

    def run(self) -> RunSummary:
        try:
            while True:
                if self._halt:
                    return self.interrupted()
                # the root alone: py_trees' BehaviourTree.tick would also visit
                # every node of the whole tree on each tick
                self._in_tick = True
                try:
                    self.root.tick_once()
                finally:
                    self._in_tick = False
                self._flush_faults()
                for listener in self.tick_listeners:
                    listener()
                status = self.root.status
                if status == Status.SUCCESS:
                    return self._summary(Outcome.VERIFIED.value)
                if status == Status.FAILURE:
                    ctx = self.failed
                    assert ctx is not None  # the action that failed reported it
                    if self.replan and self.replans < self.max_replans and self._repair(ctx):
                        continue
                    self.robot.hold()
                    advice = (
                        None
                        if ctx.outcome is not Outcome.ABORTED or ctx.preempted or retries_left(ctx)
                        else out_of_retries(ctx)
                    )
                    assert ctx.outcome is not None  # failed or aborted
                    return self._summary(ctx.outcome.value, ctx, advice)
        except Halted:  # the next action would have begun after a halt
            return self.interrupted()
        except KeyboardInterrupt as exc:
            # an interrupt between two ticks (e.g. while repair plans) halts
            # the same way; its message, if any, says why (SIGTERM's does:
            # htn.process.Terminated)
            return self.interrupted(str(exc))

    def interrupted(self, why: str = "") -> RunSummary:
        """End the run now (the tree halted, or an interrupt came between
        ticks or before the first one): running behaviours terminate, so the
        skill is preempted; the robot holds its pose; the log gets the
        ``interrupted`` event (``why``, or the halt's reason) and the
        summary, whose result is ``interrupted`` (``why``: an interrupt) or
        what :meth:`halt` was told (``preempted``)."""
        if why:
            self.halt(why)
        self.root.stop(Status.INVALID)
        self.robot.hold()
        ctx = self.running if self.running is not None and not self.running.done else None
        self.failed = ctx  # the action the run ended in
        why = self._halt or STOPPED_BY_USER
        self.emit(
            ctx,
            "interrupted",
            f"{why}; the robot holds its pose" if self.started else f"{why} before the first step",
        )
        return self._summary(self._halt_as, ctx, reason=why)

    def plan_lines(self) -> list[str]:
        """The plan as executed and repaired: verified steps, then the pending ones."""
        return [c.text for c in self.done] + [a.text for a in actions(self.root) if not a.done]

    def _summary(
        self,
        result: str,
        ctx: ActionContext | None = None,
        advice: str | None = None,
        reason: str | None = None,
    ) -> RunSummary:
        pending = sum(1 for a in actions(self.root) if not a.done)
        summary = RunSummary(
            result,
            len(self.done) + pending,
            len(self.done),
            self.retries,
            self.replans,
            round(self.robot.sim_time, 3),
            ctx.text if ctx else None,
            self.number(ctx) if ctx else None,
            self.started,
            advice,
            reason,
        )
        self.log.emit(
            None, None, "summary", None, result, **summary.as_dict(), **self.summary_extra
        )
        return summary

    # ------------------------------------------------------------ repair
    def _repair(self, ctx: ActionContext) -> bool:
        """Repair after ``ctx`` failed or was aborted: try the step again if
        its retry limit allows and it still applies in the observed state
        (with the rest of the plan after it), else re-plan its enclosing tasks."""
        observed = observed_instance(self.domain, self.instance, self.robot)
        if (
            retries_left(ctx)
            and ctx.machine is not None
            and retry_applies(ctx, self.root, self.domain, observed, self.functions)
        ):
            self.retries += 1
            self.belief = Planner.for_state(self.domain, observed.state, self.functions)
            self.failed = None
            self.emit(
                ctx,
                "retrying",
                f"retry {ctx.attempt} of {ctx.limit}, by repair: the "
                "step still applies in the observed state",
            )
            return True
        shot = next(b for b in self.root.iterate() if getattr(b, "htn_action", None) is ctx)
        repair, tried = find_repair(
            shot,
            self.root,
            self.tree_known,
            self.domain,
            observed,
            self.instance.tasks,
            self.functions,
        )
        if repair is None:
            self.emit(
                ctx,
                "replan_failed",
                f"no enclosing task has a plan from the observed state (tried {', '.join(tried)})",
                tried=tried,
            )
            return False
        self.replans += 1
        self.tree_known = True
        paths = repair.paths
        replaced = [self.nodes.of(task_node(b)) for b in repair.replaced]
        holder = self.root if repair.target is self.root else repair.target.parent
        assert holder is not None  # a task's sequence
        added = graft(repair, self.root, self._action)
        self.belief = Planner.for_state(self.domain, observed.state, self.functions)
        self.failed = None
        self.emit(
            ctx,
            "replanned",
            f"re-planned {tried[-1]} from the observed state: {len(repair.plan.steps)} new steps",
            path=repair.path,
            paths=paths,
            tasks=repair.tasks,
            steps=repair.plan.lines(),
            tried=tried,
            plan=self.plan_lines(),
        )
        pending = [a for a in actions(self.root) if not a.done]
        number = {id(a.node): len(self.done) + 1 + k for k, a in enumerate(pending)}
        self._log_tree(
            [task_node(b) for b in added],
            self.nodes.of(task_node(holder)),
            lambda n: number.get(id(n)),
            replaced,
        )
        return True


def _plan_step(node: TaskTree) -> int | None:
    """The 1-based step of an operator node of the plan's tree (its leaves index the steps)."""
    return None if node.step is None else node.step + 1
