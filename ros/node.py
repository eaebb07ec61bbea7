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
  plan starts with the very action running now, that action goes on and
  the new goal takes it as its first step, verified;
* ``resume`` (``htn ros node --resume``): a goal preempted by a newer goal
  does not end: it waits (its feedback says so), and once the newer goal
  has ended (verified, refused or cancelled) its remaining top-level tasks
  are planned again from the world model and run, the steps it verified
  staying done; its result is then the whole goal's, its summary saying it
  was resumed; not after a newer goal that failed (see :mod:`htn.ros.goals`);
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
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import rclpy
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.lifecycle import Node as LifecycleNode
from rclpy.lifecycle import State, TransitionCallbackReturn

from htn.api.agent import Agent, GoalResult
from htn.jshop.language.errors import HtnError

from .goals import Turns
from .interfaces import import_interfaces
from .shutdown import end_within, spin

if TYPE_CHECKING:
    from htn.view.live import GoalsView

POLICIES = ("preempt", "reject", "queue")
THREADS = 16  # callbacks at once: goals waiting for their turn or to resume block one each


@dataclass
class NodeSettings:
    """What ``htn ros node`` is told."""

    domain: str
    problem: str | None = None
    robot: str = "auto"  # auto: ros where a mapping file lies beside the domain
    faults: str = ""
    seed: int = 0
    replan: bool = False
    on_new_goal: str = "preempt"
    log_dir: str | None = None  # a JSON Lines log per goal, as htn run --log writes
    resume: bool = False  # a goal preempted by a newer one goes on after it
    view: tuple | None = None  # (host, port): the browser view of the goals


def robot_for(name: str, domain: str) -> str:
    """The robot back end ``name``; ``auto``: ``ros`` (the robot's own action
    servers) where a mapping file lies beside the domain, else ``symbolic``."""
    if name != "auto":
        return name
    from .mapping import beside

    return "ros" if beside(domain) is not None else "symbolic"


class HtnNode(LifecycleNode):
    """The node; ``settings`` say what it plans with, and how."""

    def __init__(self, settings: NodeSettings, name: str = "htn", managed: bool = True):
        super().__init__(name)
        self.settings, self.managed = settings, managed
        self.types = import_interfaces()
        self.agent: Agent | None = None
        self.configure_error: str | None = None
        self._group = ReentrantCallbackGroup()
        self.turns: Turns | None = None  # the goals, one at a time
        self._served: list = []
        self._events = None
        self.view: GoalsView | None = None  # the browser view of the goals, --view

    # ------------------------------------------------------------ lifecycle
    def on_configure(self, state: State) -> TransitionCallbackReturn:
        s = self.settings
        try:
            if s.log_dir:
                _log_folder(s.log_dir)
            self.agent = Agent(
                s.domain,
                s.problem,
                robot=robot_for(s.robot, s.domain),
                faults=s.faults,
                seed=s.seed,
                replan=s.replan,
            )
            if s.view is not None and self.view is None:
                from htn.api.view import start_goals_view

                self.view = start_goals_view(*s.view)
                self.get_logger().info(f"the view of the goals: {self.view.url}")
        except HtnError as exc:
            self.configure_error = str(exc)
            if self.managed:  # else serve() ends the process with it, in one line
                self.get_logger().error(f"configure: {exc}")
            return TransitionCallbackReturn.FAILURE
        self.turns = Turns(self.agent, s.on_new_goal, s.resume, s.log_dir, self._event)
        self._events = self.create_lifecycle_publisher(self.types.Event, "~/events", 100)
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: State) -> TransitionCallbackReturn:
        t, g = self.types, self._group
        self._served = [
            ActionServer(
                self,
                t.ExecuteTasks,
                "~/execute",
                execute_callback=self._execute,
                goal_callback=self._goal,
                cancel_callback=self._cancel,
                callback_group=g,
            ),
            self.create_service(t.PlanTasks, "~/plan", self._plan, callback_group=g),
            self.create_service(t.GetState, "~/state", self._state, callback_group=g),
            self.create_service(t.UpdateFacts, "~/update_facts", self._update, callback_group=g),
            self.create_subscription(t.Facts, "~/facts", self._facts, 100, callback_group=g),
        ]
        assert self.turns is not None  # configured
        self.turns.serving()
        return super().on_activate(state)

    def on_deactivate(self, state: State) -> TransitionCallbackReturn:
        if self.agent is not None:
            self.agent.preempt("the node was deactivated")
        if self.turns is not None:
            self.turns.drop_waiting("the node was deactivated")
        self._stop_serving()
        return super().on_deactivate(state)

    def on_cleanup(self, state: State) -> TransitionCallbackReturn:
        self._stop_serving()
        self._close_robot()
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: State) -> TransitionCallbackReturn:
        if self.agent is not None:
            self.agent.preempt("the node shuts down")
        if self.turns is not None:  # None after a configure that failed past the agent
            self.turns.drop_waiting("the node shuts down")
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
            self.agent, self.turns = None, None

    # ------------------------------------------------------------ the action
    def _goal(self, request) -> GoalResponse:
        assert self.turns is not None  # served while active
        if self.turns.busy() and self.settings.on_new_goal == "reject":
            self.get_logger().info("a goal is running: the new one is rejected")
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _cancel(self, goal_handle) -> CancelResponse:
        assert self.turns is not None  # served while active
        self.turns.cancel(goal_handle)
        return CancelResponse.ACCEPT

    def _execute(self, goal_handle):
        outcome = self.turns.serve(goal_handle)
        result = self._result(outcome)
        if outcome.outcome == "preempted" and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        elif outcome.outcome in ("refused", "failed", "aborted"):
            goal_handle.abort()
        else:
            goal_handle.succeed()
        return result

    def _event(self, goal_handle, rec: dict) -> None:
        """``rec`` (an event of the goal's run, as logged, or the node's
        own: ``waiting``) as the goal's feedback and on ~/events."""
        msg = self.types.Event(
            t=float(rec.get("t") or 0.0),
            sim_t=float(rec.get("sim_t") or 0.0),
            step=rec["step"] if rec.get("step") is not None else -1,
            action=rec.get("action") or "",
            event=rec["event"],
            attempt=rec.get("attempt") or 0,
            detail=str(rec.get("detail") or ""),
            record=json.dumps(rec, default=str),
        )
        feedback = self.types.ExecuteTasks.Feedback(event=msg)
        goal_handle.publish_feedback(feedback)
        if self._events is not None and self._events.is_activated:
            self._events.publish(msg)
        if self.view is not None:
            self.view.event(rec)

    def _result(self, r: GoalResult):
        return self.types.ExecuteTasks.Result(
            outcome=r.outcome,
            summary=r.summary,
            error=r.error,
            plan=list(r.plan),
            tree=r.tree,
            steps=r.steps,
            verified=r.verified,
        )

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
        assert self.agent is not None  # served while active
        try:
            self.agent.world.update(msg.add, msg.remove, msg.source or "facts")
        except HtnError as exc:
            self.get_logger().warning(f"facts refused: {exc}")


def _log_folder(path: str) -> None:
    """The folder of the goals' logs, made if missing (a one-line error if
    it cannot be, or is a file)."""
    import os

    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise HtnError(f"--log-dir: cannot make the folder: {exc.strerror or exc}", path) from exc


def serve(settings: NodeSettings, managed: bool = False, name: str = "htn", on_view=None) -> int:
    """Run the node until it is shut down (Ctrl-C, SIGTERM). Not
    ``managed``: it configures and activates itself, and a configure error
    ends it with exit code 2."""
    rclpy.init()
    node = HtnNode(settings, name, managed)
    executor = MultiThreadedExecutor(num_threads=THREADS)
    executor.add_node(node)
    try:
        if not managed:
            if node.trigger_configure() != TransitionCallbackReturn.SUCCESS:
                raise HtnError(node.configure_error or "the node could not be configured")
            node.trigger_activate()
        if node.view is not None and on_view is not None:
            on_view(node.view.url)
        spin(executor)
    except KeyboardInterrupt:
        pass
    finally:
        end_within("htn ros node")
        if node.agent is not None:
            node.agent.preempt("the node shuts down")
        if node.turns is not None:
            node.turns.drop_waiting("the node shuts down")
        executor.shutdown(timeout_sec=5.0)
        if node.view is not None:
            node.view.close()
        node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return 0


def send_goal(
    tasks: str,
    *,
    on_event=None,
    cancel_after: float | None = None,
    wait: float = 30.0,
    node_name: str = "htn",
):
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

        def on_message(m: Any) -> None:  # an Event message
            events.append(json.loads(m.record))

        client.create_subscription(types.Event, f"/{node_name}/events", on_message, 100)
        action = ActionClient(client, types.ExecuteTasks, f"/{node_name}/execute")
        if not action.wait_for_server(timeout_sec=wait):
            raise HtnError(
                f"no htn node answers on /{node_name}/execute within {wait:g} s "
                "(start one: htn ros node DOMAIN)"
            )
        # the events topic too, or the first events of the goal are lost
        deadline = time.monotonic() + wait
        while client.count_publishers(f"/{node_name}/events") == 0 and time.monotonic() < deadline:
            rclpy.spin_once(client, timeout_sec=0.05)
        sent = action.send_goal_async(types.ExecuteTasks.Goal(tasks=tasks))
        rclpy.spin_until_future_complete(client, sent)
        handle = sent.result()
        if not handle.accepted:
            raise HtnError(
                "the node rejected the goal (a goal is running and it was started "
                "with --on-new-goal reject)"
            )
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
        while (
            result.outcome != "refused"
            and time.monotonic() < until
            and not any(e.get("event") == "summary" for e in events)
        ):
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
