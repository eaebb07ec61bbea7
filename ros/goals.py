"""Whose turn it is: the goals of a robot node, run one at a time on its
:class:`~htn.api.agent.Agent` (issue 36). No middleware here: the node
(:mod:`htn.ros.node`) hands each goal's handle to :meth:`Turns.serve`, in
the goal's own thread, and a cancel to :meth:`Turns.cancel`; a handle
needs only ``request.tasks`` and ``is_cancel_requested``.

* A new goal under the ``preempt`` policy halts the goal that runs (the
  robot holds its pose; it ends ``preempted``), unless the new goal's plan
  starts with the action running now: that action goes on, and the new
  goal's run takes it as its first step, verified
  (:meth:`~htn.api.agent.Agent.preempt` with ``next_goal``). Under
  ``queue`` (and ``reject``, which the node applies first) it waits.
* A cancel halts its own goal only; a goal still waiting for its turn ends
  when the turn comes, without moving.
* ``resume``: a goal preempted by a newer goal does not end. It waits (an
  event ``waiting`` says so) until the newer goal has ended (verified,
  refused, or cancelled by its client); then its remaining top-level tasks
  are planned again from the world model and run
  (:meth:`~htn.api.agent.Agent.resume`), and its outcome is the whole
  goal's. Goals preempted in turn resume newest first, and only when no new
  goal waits for its turn. A newer goal that ends failed or aborted leaves
  the robot holding where something went wrong: the waiting goals are not
  resumed, they end ``preempted``, saying why; so does a waiting goal that
  is cancelled, and every waiting goal when the node stops serving.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import replace
from typing import overload

from htn.api.agent import Agent, GoalResult

NEWER = "preempted by a newer goal"
CANCELLED = "cancelled by the client"


class Goal:
    """A goal as the node serves it: its handle, its number (its log's),
    and what other threads tell it."""

    def __init__(self, handle):
        self.handle = handle
        self.tasks: str = handle.request.tasks
        self.number = 0
        self.halt: str | None = None  # a halt its run has yet to take (see Turns._halt)
        self.why: str | None = None  # why it was last asked to halt
        self.waits = False  # preempted, it waits to resume
        self.wake = threading.Event()  # ... and its turn came, or it ends (drop)
        self.drop: str | None = None  # why it is not resumed

    def cancelled(self) -> bool:
        return self.handle.is_cancel_requested


class Turns:
    """The goals of one agent, one at a time. ``policy``: what a new goal
    does to the one running (``preempt``, ``queue``; ``reject`` is the
    node's to apply); ``resume``: see the module's docstring; ``log_dir``:
    a JSON Lines log per run (``goal-0001.jsonl``, and a resumed run's
    ``goal-0001-resumed-1.jsonl``); ``emit(handle, record)``: each event of
    a goal, as logged (and the ``waiting`` event)."""

    def __init__(
        self,
        agent: Agent,
        policy: str = "preempt",
        resume: bool = False,
        log_dir: str | None = None,
        emit: Callable[[object, dict], None] = lambda handle, rec: None,
    ):
        self.agent, self.policy, self.resume, self.log_dir = agent, policy, resume, log_dir
        self.emit = emit
        self._turn = threading.Lock()  # one goal runs at a time
        self._gate = threading.Lock()  # the fields below, between goals' threads
        self._waiting = 0  # new goals waiting for their turn
        self._current: Goal | None = None  # the goal whose turn it is
        self._resumable: list = []  # preempted goals waiting to resume, newest last
        self._serving = True  # preempted goals may wait to resume
        self._goals = 0

    def busy(self) -> bool:
        """Does a goal run, or wait for its turn?"""
        return self._turn.locked() or bool(self._waiting)

    def serving(self) -> None:
        """Preempted goals may wait to resume again (the node is active)."""
        with self._gate:
            self._serving = True

    # ------------------------------------------------------------ a goal
    def serve(self, handle) -> GoalResult:
        """Run the goal of ``handle`` when its turn comes (preempting the
        one that runs, under ``preempt``), resume it as often as it is
        preempted (``resume``); its outcome, once it has ended."""
        goal = Goal(handle)
        with self._gate:
            self._waiting += 1
            running = self._current
        if self.policy == "preempt" and running is not None:
            self._halt(running, NEWER, next_goal=goal.tasks)
        outcome = self._take_turn(goal, None)
        while goal.waits:
            self.emit(
                handle,
                {
                    "event": "waiting",
                    "detail": (
                        f"{NEWER} after {outcome.verified} verified step(s): its remaining tasks "
                        f"{outcome.remaining} resume when the newer goal has ended"
                    ),
                },
            )
            goal.wake.wait()
            if goal.drop is not None:
                return replace(outcome, summary=f"{outcome.summary}; not resumed: {goal.drop}")
            outcome = self._take_turn(goal, outcome) or outcome
        return outcome

    def cancel(self, handle) -> None:
        """Cancel that goal only: halt it if it runs, end it if it waits to
        resume (a goal waiting for its first turn ends when it comes)."""
        with self._gate:
            current = self._current
            for g in [g for g in self._resumable if g.handle is handle]:
                self._resumable.remove(g)
                g.drop = "cancelled by the client while it waited to resume"
                g.wake.set()
        if current is not None and current.handle is handle:
            self._halt(current, CANCELLED)

    def drop_waiting(self, why: str) -> None:
        """End every goal waiting to resume (``preempted``, saying ``why``
        it is not resumed); none waits to resume until :meth:`serving`."""
        with self._gate:
            self._serving = False
            self._drop(why)

    # ------------------------------------------------------------ inside
    def _halt(self, goal: Goal, why: str, next_goal: str | None = None) -> None:
        """Preempt ``goal``'s run (``next_goal``: the tasks of the goal that
        preempts it, whose plan may go on with the running action); if it
        has not begun yet, its run takes the halt with its first event."""
        goal.why = why
        if not self.agent.preempt(why, next_goal=next_goal):
            goal.halt = why

    @overload
    def _take_turn(self, goal: Goal, before: None) -> GoalResult: ...
    @overload
    def _take_turn(self, goal: Goal, before: GoalResult) -> GoalResult | None: ...
    def _take_turn(self, goal: Goal, before: GoalResult | None) -> GoalResult | None:
        """Run ``goal`` (``before``: resume it, preempted as that) when its
        turn comes, then decide who goes on. None: a goal to resume gave
        way to a new goal waiting for its turn, and waits again."""
        with self._turn:
            with self._gate:
                if before is not None and self._waiting:  # a new goal goes first
                    goal.wake.clear()
                    self._resumable.append(goal)
                    return None
                goal.waits = False
                if before is None:
                    self._waiting -= 1
                    self._goals += 1
                    goal.number = self._goals
                self._current, goal.halt, goal.why = goal, None, None
            try:
                outcome = self._run(goal, before)
            finally:
                with self._gate:
                    self._current = None
            self._after(goal, outcome)
            return outcome

    def _run(self, goal: Goal, before: GoalResult | None) -> GoalResult:
        if goal.cancelled():
            return before or GoalResult("preempted", "preempted before it started")
        log = None
        if self.log_dir:
            again = f"-resumed-{before.resumed + 1}" if before is not None else ""
            log = f"{self.log_dir}/goal-{goal.number:04d}{again}.jsonl"

        def on_event(rec):
            if goal.halt is not None:  # asked before its run had begun
                why, goal.halt = goal.halt, None
                self.agent.preempt(why)
            self.emit(goal.handle, rec)

        if before is None:
            return self.agent.execute(goal.tasks, log=log, on_event=on_event)
        return self.agent.resume(before, log=log, on_event=on_event)

    def _after(self, goal: Goal, outcome: GoalResult) -> None:
        """After ``goal``'s run: it waits to resume (preempted by a newer
        goal, with ``resume``), or it has ended; then the newest waiting
        goal is woken, unless a new goal waits (which wakes it when it
        ends), or the goal ended failed or aborted (the waiting ones end)."""
        with self._gate:
            if (
                self.resume
                and self._serving
                and outcome.outcome == "preempted"
                and outcome.remaining
                and goal.why == NEWER
                and not goal.cancelled()
            ):
                goal.waits = True
                goal.wake.clear()
                self._resumable.append(goal)
            elif outcome.outcome in ("failed", "aborted"):
                self._drop(f"the goal after it ended {outcome.outcome}")
            if self._resumable and not self._waiting:
                self._resumable.pop().wake.set()

    def _drop(self, why: str) -> None:
        for g in self._resumable:
            g.drop = why
            g.wake.set()
        self._resumable = []
