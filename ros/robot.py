"""``--robot ros``: a robot back end whose skills are ROS 2 action goals to
the robot's own action servers and whose checks are service calls (or a
topic's last message), as the mapping file beside the domain names them
(:mod:`htn.ros.mapping`). This module holds the rclpy of htn's robot side.

A skill is a generator the task executor ticks (see
:mod:`htn.robot.interface`): it waits for the action server (up to the
mapping's ``wait``), sends the goal, and on each tick looks whether the result
came, whether the server is still there and whether the robot still speaks
(its pose topic); halting it (closing the generator) cancels the goal. It
ends failed with the reason when the server is missing, rejects the goal or
goes away (``the action server /robot/skill/grasp went away``), never with
an exception. A check waits at most ``wait`` seconds for its service.

What the robot observes (``observe``: the mapping's ``observe`` service) is
asked before each goal of a long-lived planner (``observes_world``), so that
a restarted or moved robot is planned for as it is; the faults a simulated
robot injects arrive on ``<namespace>/faults`` and become the log's
``fault`` events; the robot's clock is its pose topic's stamp.
"""

from __future__ import annotations

import json
import threading
import time

import rclpy
from action_msgs.msg import GoalStatus
from rclpy.executors import SingleThreadedExecutor

from htn.jshop.language.errors import HtnError
from htn.robot.interface import Check, Robot, SkillResult

from . import mapping as mapping_file
from .action_client import OrderedActionClient
from .interfaces import InterfaceBuildError, import_interfaces, import_type

TICK = 0.005  # s a tick waits for a result before the executor goes on
SILENT = 1.5  # s without a pose message that mean the robot has gone
RETRY = 0.25  # s before a service call without answer is sent again
ENDED = (GoalStatus.STATUS_SUCCEEDED, GoalStatus.STATUS_ABORTED, GoalStatus.STATUS_CANCELED)


def make_robot(request):
    """The ``ros`` back end for a :class:`~htn.robot.backends.RobotRequest`:
    the mapping file beside the domain (or the default names)."""
    if request.faults:
        raise HtnError(
            "--faults: the ros robot injects no faults itself (a simulated robot "
            "does: htn ros robot --sim --faults ...)"
        )
    found = mapping_file.beside(request.domain.file) if request.domain.file else None
    table = mapping_file.read(found) if found else mapping_file.default()
    facts = [(a.pred, tuple(a.args)) for a in request.instance.state]
    return RosRobot(table, facts, request.domain.dynamic_predicates())


class RosRobot(Robot):
    """The robot behind ROS 2 action servers and services named by ``table``
    (a :class:`~htn.ros.mapping.Mapping`); ``facts``: the world model's
    ``(pred, args)`` pairs the goals' ``where`` patterns are matched in, of
    which an observation replaces those of the ``dynamic`` predicates."""

    steps_per_tick = 1

    def __init__(
        self, table: mapping_file.Mapping, facts: list, dynamic=(), node_name: str = "htn_robot"
    ):
        try:
            self.types = import_interfaces()
        except InterfaceBuildError as exc:
            raise HtnError(str(exc)) from exc
        self.mapping, self.facts, self.dynamic = table, list(facts), set(dynamic)
        self.observes_world = bool(table.observe)
        self.injected: list[dict] = []
        self._clock = 0.0
        self._heard = 0.0  # monotonic time of the last pose message
        self._owns_rclpy = not rclpy.ok()
        if self._owns_rclpy:
            rclpy.init()
        self.node = rclpy.create_node(node_name)
        self._lock = threading.Lock()
        self._actions: dict[str, OrderedActionClient] = {}
        self._services: dict = {}
        self._topics: dict = {}  # topic check name -> last message
        self._goals: dict = {}  # id -> a goal's sending future, until it ends
        if table.pose:
            from geometry_msgs.msg import PoseStamped

            self.node.create_subscription(PoseStamped, table.full(table.pose), self._pose, 10)
        self.node.create_subscription(self.types.Event, table.full("faults"), self._fault, 100)
        self._executor = SingleThreadedExecutor()
        self._executor.add_node(self.node)
        self._spinning = threading.Thread(target=self._spin, name="htn-ros-robot", daemon=True)
        self._spinning.start()

    # ------------------------------------------------------------ the middleware
    def _spin(self) -> None:
        try:
            while rclpy.ok() and not getattr(self, "_closed", False):
                self._executor.spin_once(timeout_sec=0.05)
        except Exception:  # the context shut down under us: nothing left to serve
            pass

    def _pose(self, msg) -> None:
        stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
        self._clock = max(self._clock, stamp)
        self._heard = time.monotonic()

    def _fault(self, msg) -> None:
        try:
            kind = json.loads(msg.record).get("kind", msg.event)
        except ValueError:
            kind = msg.event
        self.injected.append({"kind": kind, "sim_t": round(msg.sim_t, 4), "detail": msg.detail})

    @property
    def sim_time(self) -> float:  # type: ignore[override]
        return self._clock

    @sim_time.setter
    def sim_time(self, value: float) -> None:
        self._clock = value

    def _action(self, call) -> OrderedActionClient:
        with self._lock:
            client = self._actions.get(call.name)
            if client is None:
                client = OrderedActionClient(self.node, import_type(call.type), call.name)
                self._actions[call.name] = client
            return client

    def _service(self, call):
        with self._lock:
            client = self._services.get(call.name)
            if client is None:
                kind = import_type(call.type)
                client = (kind, self.node.create_client(kind, call.name))
                self._services[call.name] = client
            return client

    def _silent(self, since: float) -> bool:
        """The robot's pose topic, heard before, has been silent too long,
        counting from ``since`` at the earliest (when the skill began: a
        robot node started again is not silent before it could speak)."""
        return (
            bool(self.mapping.pose)
            and self._heard > 0
            and time.monotonic() - max(self._heard, since) > SILENT
        )

    # ------------------------------------------------------------ skills
    def act(self, name: str, *args):
        return self._run(name, self.mapping.skill(name), args)

    def _run(self, name: str, call, args: tuple):
        try:
            kind = import_type(call.type)
            goal = mapping_file.fill(kind.Goal(), call.values(args, self.facts))
            client = self._action(call)
        except (HtnError, InterfaceBuildError) as exc:
            return SkillResult(False, f"{name}: {exc}")
        until = time.monotonic() + self.mapping.wait
        while not client.server_is_ready():
            if time.monotonic() > until:
                return SkillResult(
                    False, f"no action server {call.name} (waited {self.mapping.wait:g} s)"
                )
            yield
            time.sleep(TICK)
        began = time.monotonic()

        def gone() -> bool:
            return not client.server_is_ready() or self._silent(began)

        sent = client.send_goal_async(goal, feedback_callback=self._feedback)
        self._goals[id(sent)] = sent  # until it ends: hold() cancels it
        try:
            ready, until = _event(sent), time.monotonic() + self.mapping.wait
            while not sent.done():
                if gone():
                    return SkillResult(False, f"the action server {call.name} went away")
                if time.monotonic() > until:
                    return SkillResult(
                        False,
                        f"the action server {call.name} did not answer "
                        f"the goal within {self.mapping.wait:g} s",
                    )
                yield
                ready.wait(TICK)
            handle = sent.result()
            if not handle.accepted:
                self._goals.pop(id(sent), None)
                return SkillResult(False, f"the action server {call.name} rejected the goal")
            done = handle.get_result_async()
            ready, asked = _event(done), time.monotonic()
            while not done.done():
                if gone():
                    return SkillResult(False, f"the action server {call.name} went away")
                if handle.status in ENDED and time.monotonic() - asked > 4 * RETRY:
                    # the goal has ended (its status says so) but its result has
                    # not come: the request may have gone out before the server
                    # matched this client's reply channel; ask again
                    done = handle.get_result_async()
                    ready, asked = _event(done), time.monotonic()
                yield
                ready.wait(TICK)
            self._goals.pop(id(sent), None)
            return self._ended(call, done.result())
        finally:
            if self._goals.pop(id(sent), None) is not None:
                _cancel(sent)  # halted, or the server went: cancel the goal, sent or not

    def _feedback(self, msg) -> None:
        sim_t = getattr(msg.feedback, "sim_t", None)
        if sim_t is not None:
            self._clock = max(self._clock, float(sim_t))

    def _ended(self, call, response) -> SkillResult:
        result, status = response.result, response.status
        sim_t = getattr(result, "sim_t", None)
        if sim_t is not None:
            self._clock = max(self._clock, float(sim_t))
        detail = getattr(result, "detail", "") or getattr(result, "error_msg", "")
        if status != GoalStatus.STATUS_SUCCEEDED:
            names = {GoalStatus.STATUS_ABORTED: "aborted", GoalStatus.STATUS_CANCELED: "canceled"}
            return SkillResult(
                False,
                f"{call.name} {names.get(status, f'status {status}')}"
                + (f": {detail}" if detail else ""),
            )
        ok = bool(getattr(result, "ok", True)) and not getattr(result, "error_code", 0)
        return SkillResult(ok, detail or ("done" if ok else "failed"))

    # ------------------------------------------------------------ checks
    def check(self, name: str, *args) -> Check:
        call = self.mapping.check(name)
        try:
            if call.is_topic:
                return self._topic_check(name, call)
            kind, client = self._service(call)
            request = mapping_file.fill(kind.Request(), call.values(args, self.facts))
        except (HtnError, InterfaceBuildError) as exc:
            return Check(False, f"{name}: {exc}")
        response = self._call(client, request)
        if response is None:
            return Check(False, f"{name} is not observable: no answer from {call.name}")
        ok = getattr(response, "ok", getattr(response, "success", False))
        return Check(bool(ok), getattr(response, "detail", getattr(response, "message", "")))

    def _call(self, client, request):
        """The service's response, or None when it is not there or does not
        answer within the mapping's ``wait``."""
        until = time.monotonic() + self.mapping.wait
        while not client.service_is_ready():
            if time.monotonic() > until:
                return None
            time.sleep(TICK)
        # asked again when no answer comes within a retry interval: a
        # service is "ready" once its server is discovered, which may be
        # before the server has matched this client's reply channel (the
        # first request is then lost); checks have no side effects
        end, retry = until + self.mapping.wait, RETRY
        while time.monotonic() < end:
            future = client.call_async(request)
            if _event(future).wait(min(retry, max(0.0, end - time.monotonic()))):
                return future.result()
            client.remove_pending_request(future)
            if not client.service_is_ready():
                return None
            retry *= 2
        return None

    def _topic_check(self, name: str, call) -> Check:
        if name not in self._topics:
            self._topics[name] = None
            self.node.create_subscription(
                import_type(call.type),
                call.name,
                lambda m: self._topics.__setitem__(name, m),
                10,
            )
        until = time.monotonic() + self.mapping.wait
        while self._topics[name] is None and time.monotonic() < until:
            time.sleep(TICK)
        msg = self._topics[name]
        if msg is None:
            return Check(False, f"{name} is not observable: nothing on {call.name}")
        value = msg
        for part in call.field_name.split("."):
            value = getattr(value, part, None)
        return Check(value == call.equals, f"{call.name} {call.field_name} = {value!r}")

    # ------------------------------------------------------------ state
    def observe(self) -> list[tuple[str, tuple]]:
        if not self.mapping.observe:
            return []
        call = mapping_file.Call(
            self.mapping.full(self.mapping.observe), "htn_interfaces/srv/GetState"
        )
        _, client = self._service(call)
        response = self._call(client, self.types.GetState.Request(pattern=""))
        if response is None:
            return []
        seen = [parse_fact(text) for text in response.facts]
        self.facts = [(p, a) for p, a in self.facts if p not in self.dynamic] + seen
        return seen

    def hold(self) -> None:
        for key, sent in list(self._goals.items()):
            self._goals.pop(key, None)
            _cancel(sent)

    def close(self) -> None:
        self.hold()
        self._closed = True
        self._spinning.join(timeout=1.0)
        self._executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        if self._owns_rclpy and rclpy.ok():
            rclpy.shutdown()


def _cancel(sent) -> None:
    """Cancel the goal whose sending is the future ``sent``: now if the
    server has answered, else as soon as it does (a goal halted before it
    was accepted must not run on)."""

    def cancel(future) -> None:
        handle = future.result()
        if handle is not None and handle.accepted:
            handle.cancel_goal_async()
            _cancel_again(handle, tries=5)

    if sent.done():
        cancel(sent)
    else:
        sent.add_done_callback(cancel)


def _cancel_again(handle, tries: int) -> None:
    """Send the cancel again while the goal's status still says it runs (a
    request can be dropped when the server has not yet matched this client's
    reply channel: a robot must not drive on), every 0.3 s, ``tries`` times."""

    def check() -> None:
        if handle.status in (GoalStatus.STATUS_ACCEPTED, GoalStatus.STATUS_EXECUTING):
            handle.cancel_goal_async()
            if tries > 1:
                _cancel_again(handle, tries - 1)

    timer = threading.Timer(0.3, check)
    timer.daemon = True
    timer.start()


def _event(future) -> threading.Event:
    """An event set when ``future`` is done (by the spinning thread)."""
    event = threading.Event()
    future.add_done_callback(lambda _: event.set())
    return event


def parse_fact(text: str) -> tuple[str, tuple]:
    """``(at robby 1.5)`` → ``("at", ("robby", 1.5))``: numbers as floats,
    as the simulated robots observe them."""
    tokens = text.strip().removeprefix("(").removesuffix(")").split()
    if not tokens:
        raise HtnError(f"not a fact: {text!r}")

    def value(token: str):
        try:
            return float(token)
        except ValueError:
            return token

    return tokens[0], tuple(value(t) for t in tokens[1:])
