"""The htn planning-and-execution node: a managed (lifecycle) ROS 2 node
around :class:`htn.api.agent.Agent`. Everything rclpy-specific of htn's
node side is in this module; the planning, the executor and the world
model are the use cases', unchanged.

Interfaces (``htn_interfaces``, see ``ros/interfaces/``):

* action ``~/execute`` (``ExecuteTasks``): the goal's tasks are planned from
  the world model and run; each executor event is feedback and goes out on
  ``~/events`` (``Event``; the action client drops feedback that comes after
  the result, a topic does not); the result says verified / failed /
  aborted / preempted / refused, with the summary line, the located error of
  a refused goal and the plan with its task tree;
* a cancel, or a new goal under ``on_new_goal="preempt"`` (the default),
  halts the running goal at its current action: the robot holds its pose
  and the goal ends ``preempted`` (its log too); ``"reject"`` refuses the
  new goal while one runs, ``"queue"`` runs it after. Where the new goal's
  plan (from what the running goal believes) starts with the very action
  running now, that action goes on to its end instead of being cancelled
  and started again: the running goal halts before its next action, and the
  new goal's run takes it as its first step, verified;
* ``resume`` (``htn ros node --resume``): a goal preempted by a newer goal
  does not end: its feedback says it waits (an event ``waiting``), and once
  the newer goal has ended (verified, refused, or cancelled by its client)
  its remaining top-level tasks are planned again from the world model and
  run, the steps it verified staying done; its result is then the whole
  goal's, as usual, its summary saying it was resumed. Goals preempted in
  turn resume newest first, and only when no new goal waits. If the newer
  goal ends failed or aborted (the robot holds where something went wrong),
  the waiting goals are not resumed: they end ``preempted``, saying why; so
  do they when cancelled while they wait, or when the node is deactivated;
* services ``~/plan`` (``PlanTasks``: plan only), ``~/state`` (``GetState``:
  the facts matching a pattern) and ``~/update_facts`` (``UpdateFacts``),
  and the topic ``~/facts`` (``Facts``) for what other nodes observe: a fact
  the domain does not know is refused with the reason, nothing is changed.

Lifecycle: ``configure`` reads the domain and the problem and builds the
robot (a located error fails the transition and is logged); ``activate``
starts serving; ``deactivate`` preempts a running goal and stops serving.
"""
from __future__ import annotations

import json
import threading
from dataclasses import dataclass, replace
from typing import Optional

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.lifecycle import Node as LifecycleNode
from rclpy.lifecycle import State, TransitionCallbackReturn

from htn.api.agent import Agent, GoalResult
from htn.jshop.language.errors import HtnError

from .interfaces import import_interfaces

POLICIES = ("preempt", "reject", "queue")
NEWER = "preempted by a newer goal"
CANCELLED = "cancelled by the client"
THREADS = 16        # callbacks at once: goals waiting for their turn or to resume block one each


@dataclass
class NodeSettings:
    """What ``htn ros node`` is told."""
    domain: str
    problem: Optional[str] = None
    robot: str = "auto"                 # auto: ros where a mapping file lies beside the domain
    faults: str = ""
    seed: int = 0
    replan: bool = False
    on_new_goal: str = "preempt"
    log_dir: Optional[str] = None       # a JSON Lines log per goal, as htn run --log writes
    resume: bool = False                # a goal preempted by a newer one goes on after it


class _Goal:
    """A goal of the action as the node serves it: its handle, its number
    (its log's), and what other threads tell it."""

    def __init__(self, handle):
        self.handle = handle
        self.tasks: str = handle.request.tasks
        self.number = 0
        self.halt: Optional[str] = None     # a halt its run has yet to take (see HtnNode._halt)
        self.why: Optional[str] = None      # why it was last asked to halt
        self.waits = False                  # preempted, it waits to resume
        self.wake = threading.Event()       # ... and its turn came, or it ends (drop)
        self.drop: Optional[str] = None     # why it is not resumed

    def cancelled(self) -> bool:
        return self.handle.is_cancel_requested


def robot_for(name: str, domain: str) -> str:
    """The robot back end ``name``; ``auto``: ``ros`` (the robot's own action
    servers) where a mapping file lies beside the domain, else ``symbolic``."""
    if name != "auto":
        return name
    from .mapping import beside
    return "ros" if beside(domain) is not None else "symbolic"


class HtnNode(LifecycleNode):
    """The node; ``settings`` say what it plans with, and how."""

    def __init__(self, settings: NodeSettings, name: str = "htn"):
        super().__init__(name)
        self.settings = settings
        self.types = import_interfaces()
        self.agent: Optional[Agent] = None
        self.configure_error: Optional[str] = None
        self._group = ReentrantCallbackGroup()
        self._turn = threading.Lock()           # one goal runs at a time
        self._gate = threading.Lock()           # the fields below, between goals' threads
        self._waiting = 0                       # new goals waiting for their turn
        self._current: Optional[_Goal] = None   # the goal whose turn it is
        self._resumable: list = []              # preempted goals waiting to resume, newest last
        self._serving = False                   # active: preempted goals may wait to resume
        self._served: list = []
        self._events = None
        self._goals = 0

    # ------------------------------------------------------------ lifecycle
    def on_configure(self, state: State) -> TransitionCallbackReturn:
        s = self.settings
        try:
            self.agent = Agent(s.domain, s.problem, robot=robot_for(s.robot, s.domain), faults=s.faults, seed=s.seed,
                               replan=s.replan)
        except HtnError as exc:
            self.configure_error = str(exc)
            self.get_logger().error(f"configure: {exc}")
            return TransitionCallbackReturn.FAILURE
        self._events = self.create_lifecycle_publisher(self.types.Event, "~/events", 100)
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: State) -> TransitionCallbackReturn:
        t, g = self.types, self._group
        self._served = [
            ActionServer(self, t.ExecuteTasks, "~/execute", execute_callback=self._execute,
                         goal_callback=self._goal, cancel_callback=self._cancel,
                         callback_group=g),
            self.create_service(t.PlanTasks, "~/plan", self._plan, callback_group=g),
            self.create_service(t.GetState, "~/state", self._state, callback_group=g),
            self.create_service(t.UpdateFacts, "~/update_facts", self._update, callback_group=g),
            self.create_subscription(t.Facts, "~/facts", self._facts, 100, callback_group=g),
        ]
        with self._gate:
            self._serving = True
        return super().on_activate(state)

    def on_deactivate(self, state: State) -> TransitionCallbackReturn:
        if self.agent is not None:
            self.agent.preempt("the node was deactivated")
        self.drop_waiting("the node was deactivated")
        self._stop_serving()
        return super().on_deactivate(state)

    def on_cleanup(self, state: State) -> TransitionCallbackReturn:
        self._stop_serving()
        self._close_robot()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: State) -> TransitionCallbackReturn:
        if self.agent is not None:
            self.agent.preempt("the node shuts down")
        self.drop_waiting("the node shuts down")
        self._stop_serving()
        self._close_robot()
        return TransitionCallbackReturn.SUCCESS

    def _stop_serving(self) -> None:
        for s in self._served:
            if isinstance(s, ActionServer):
                s.destroy()
            elif hasattr(s, "srv_name"):
                self.destroy_service(s)
            else:
                self.destroy_subscription(s)
        self._served = []

    def _close_robot(self) -> None:
        if self.agent is not None:
            self.agent.robot.close()
            self.agent = None

    # ------------------------------------------------------------ the action
    def _goal(self, request) -> GoalResponse:
        busy = self._turn.locked() or self._waiting
        if busy and self.settings.on_new_goal == "reject":
            self.get_logger().info("a goal is running: the new one is rejected")
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _cancel(self, goal_handle) -> CancelResponse:
        """Cancel that goal only: halt it if it runs, end it if it waits to
        resume (a goal waiting for its first turn ends when it comes)."""
        with self._gate:
            current = self._current
            waiting = [g for g in self._resumable if g.handle is goal_handle]
            for g in waiting:
                self._resumable.remove(g)
                g.drop = "cancelled by the client while it waited to resume"
                g.wake.set()
        if current is not None and current.handle is goal_handle:
            self._halt(current, CANCELLED)
        return CancelResponse.ACCEPT

    def _halt(self, goal: _Goal, why: str, next_goal: Optional[str] = None) -> None:
        """Preempt ``goal``'s run (``next_goal``: the tasks of the goal that
        preempts it, whose plan may go on with the running action); if it
        has not begun yet, its run takes the halt with its first event."""
        goal.why = why
        if not self.agent.preempt(why, next_goal=next_goal):
            goal.halt = why

    def _execute(self, goal_handle):
        goal = _Goal(goal_handle)
        with self._gate:
            self._waiting += 1
            running = self._current
        if self.settings.on_new_goal == "preempt" and running is not None:
            self._halt(running, NEWER, next_goal=goal.tasks)
        outcome = self._take_turn(goal, None)
        while goal.waits:
            self._event(goal_handle, {"event": "waiting", "detail": (
                f"{NEWER} after {outcome.verified} verified step(s): its remaining tasks "
                f"{outcome.remaining} resume when the newer goal has ended")})
            goal.wake.wait()
            if goal.drop is not None:
                outcome = replace(outcome, summary=f"{outcome.summary}; not resumed: {goal.drop}")
                break
            outcome = self._take_turn(goal, outcome) or outcome
        result = self._result(outcome)
        if outcome.outcome == "preempted" and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        elif outcome.outcome in ("refused", "failed", "aborted"):
            goal_handle.abort()
        else:
            goal_handle.succeed()
        return result

    def _take_turn(self, goal: _Goal, before: Optional[GoalResult]) -> Optional[GoalResult]:
        """Run ``goal`` (``before``: resume it, preempted as that) when its
        turn comes; then decide who goes on (see the module's docstring).
        None: a resumed goal gave way to a new goal waiting, and waits again."""
        with self._turn:
            with self._gate:
                if before is not None and self._waiting:    # a new goal goes first
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

    def _run(self, goal: _Goal, before: Optional[GoalResult]) -> GoalResult:
        if goal.cancelled():
            return before or GoalResult("preempted", "preempted before it started")
        log = None
        if self.settings.log_dir:
            again = f"-resumed-{before.resumed + 1}" if before is not None else ""
            log = f"{self.settings.log_dir}/goal-{goal.number:04d}{again}.jsonl"

        def on_event(rec):
            if goal.halt is not None:       # asked before its run had begun
                why, goal.halt = goal.halt, None
                self.agent.preempt(why)
            self._event(goal.handle, rec)
        if before is None:
            return self.agent.execute(goal.tasks, log=log, on_event=on_event)
        return self.agent.resume(before, log=log, on_event=on_event)

    def _after(self, goal: _Goal, outcome: GoalResult) -> None:
        """After ``goal``'s run: it waits to resume (preempted by a newer
        goal, with ``resume``), or it has ended; then the newest waiting
        goal is woken, unless a new goal waits (it wakes it when it ends),
        or the ended goal failed (the waiting goals end)."""
        with self._gate:
            if self.settings.resume and self._serving and outcome.outcome == "preempted" \
                    and outcome.remaining and goal.why == NEWER and not goal.cancelled():
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

    def drop_waiting(self, why: str) -> None:
        """End every goal waiting to resume (``preempted``, saying ``why``
        it is not resumed); no goal waits to resume until the node is
        activated again."""
        with self._gate:
            self._serving = False
            self._drop(why)

    def _event(self, goal_handle, rec: dict) -> None:
        """``rec`` (an event of the goal's run, as logged, or the node's
        own: ``waiting``) as the goal's feedback and on ~/events."""
        msg = self.types.Event(t=float(rec.get("t") or 0.0), sim_t=float(rec.get("sim_t") or 0.0),
                               step=rec["step"] if rec.get("step") is not None else -1,
                               action=rec.get("action") or "", event=rec["event"],
                               attempt=rec.get("attempt") or 0, detail=str(rec.get("detail") or ""),
                               record=json.dumps(rec, default=str))
        feedback = self.types.ExecuteTasks.Feedback(event=msg)
        goal_handle.publish_feedback(feedback)
        if self._events is not None and self._events.is_activated:
            self._events.publish(msg)

    def _result(self, r: GoalResult):
        return self.types.ExecuteTasks.Result(outcome=r.outcome, summary=r.summary, error=r.error,
                                              plan=list(r.plan), tree=r.tree, steps=r.steps,
                                              verified=r.verified)

    # ------------------------------------------------------------ services
    def _plan(self, request, response):
        try:
            p = self.agent.plan(request.tasks)
        except HtnError as exc:
            response.ok, response.error = False, str(exc)
            return response
        if p is None:
            response.ok, response.error = False, "no plan reaches the goal from the current state"
            return response
        response.ok, response.steps, response.cost = True, p.lines(), float(p.cost)
        response.tree = json.dumps(p.tree.to_dict()) if p.tree is not None else ""
        return response

    def _state(self, request, response):
        try:
            response.facts = self.agent.world.query(request.pattern)
        except HtnError as exc:
            self.get_logger().warning(f"state: {exc}")
            response.facts = []
        return response

    def _update(self, request, response):
        f = request.facts
        try:
            response.facts = self.agent.world.update(f.add, f.remove, f.source or "facts")
            response.ok = True
        except HtnError as exc:
            response.ok, response.error = False, str(exc)
            response.facts = len(self.agent.world.facts())
        return response

    def _facts(self, msg) -> None:
        try:
            self.agent.world.update(msg.add, msg.remove, msg.source or "facts")
        except HtnError as exc:
            self.get_logger().warning(f"facts refused: {exc}")


def serve(settings: NodeSettings, managed: bool = False, name: str = "htn") -> int:
    """Run the node until it is shut down (Ctrl-C, SIGTERM). Not
    ``managed``: it configures and activates itself, and a configure error
    ends it with exit code 2."""
    rclpy.init()
    node = HtnNode(settings, name)
    executor = MultiThreadedExecutor(num_threads=THREADS)
    executor.add_node(node)
    try:
        if not managed:
            if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
                raise HtnError(node.configure_error or "the node could not be configured")
            node.trigger_activate()
        executor.spin()
    except KeyboardInterrupt:
        pass
    finally:
        if node.agent is not None:
            node.agent.preempt("the node shuts down")
        node.drop_waiting("the node shuts down")
        executor.shutdown()
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0


def send_goal(tasks: str, *, on_event=None, cancel_after: Optional[float] = None,
              wait: float = 30.0, node_name: str = "htn"):
    """Send ``tasks`` to the node's ``/NODE/execute`` and wait for its
    result (the ``ExecuteTasks`` result); ``on_event`` gets each event (a
    dict, as logged) from the ``/NODE/events`` topic, in order and complete
    (the action's feedback may be dropped after the result). A node that
    is not there within ``wait`` seconds is an :class:`HtnError`.
    ``cancel_after``: cancel the goal after that many seconds."""
    import time

    from rclpy.action import ActionClient

    types = import_interfaces()
    rclpy.init()
    client = rclpy.create_node("htn_send")
    try:
        events: list = []
        client.create_subscription(types.Event, f"/{node_name}/events",
                                   lambda m: events.append(json.loads(m.record)), 100)
        action = ActionClient(client, types.ExecuteTasks, f"/{node_name}/execute")
        if not action.wait_for_server(timeout_sec=wait):
            raise HtnError(f"no htn node answers on /{node_name}/execute within {wait:g} s "
                           "(start one: htn ros node DOMAIN)")
        # the events topic too, or the first events of the goal are lost
        deadline = time.monotonic() + wait
        while client.count_publishers(f"/{node_name}/events") == 0 \
                and time.monotonic() < deadline:
            rclpy.spin_once(client, timeout_sec=0.05)
        sent = action.send_goal_async(types.ExecuteTasks.Goal(tasks=tasks))
        rclpy.spin_until_future_complete(client, sent)
        handle = sent.result()
        if not handle.accepted:
            raise HtnError("the node rejected the goal (a goal is running and it was started "
                           "with --on-new-goal reject)")
        done = handle.get_result_async()
        cancel_at = None if cancel_after is None else time.monotonic() + cancel_after
        shown = 0
        while not done.done():
            rclpy.spin_once(client, timeout_sec=0.02)
            shown = _show(events, shown, on_event)
            if cancel_at is not None and time.monotonic() >= cancel_at:
                handle.cancel_goal_async()
                cancel_at = None
        result = done.result().result
        # the summary event is the log's last: wait for it (briefly) before returning
        until = time.monotonic() + 2.0
        while result.outcome != "refused" and time.monotonic() < until \
                and not any(e.get("event") == "summary" for e in events):
            rclpy.spin_once(client, timeout_sec=0.02)
        _show(events, shown, on_event)
        return result
    finally:
        client.destroy_node()
        rclpy.shutdown()


def _show(events: list, shown: int, on_event) -> int:
    for rec in events[shown:]:
        if on_event is not None:
            on_event(rec)
    return len(events)
