"""A robot back end served over ROS 2 (``htn ros robot --sim``): each skill an
action server, each check a service, its pose on a topic. This module holds
the rclpy of that robot node; the robot itself is any
:class:`~htn.robot.interface.Robot` (the PyBullet domestic and kitchen robots).

Names (under the namespace, default ``/robot``), which are what the mapping
file (:mod:`htn.ros.mapping`) assumes for anything it does not name:

* ``skill/<name>``: ``htn_interfaces/action/Skill`` for every skill; a cancel
  stops the skill where it is and the robot holds its pose;
* ``/navigate_to_pose`` (absolute, as Nav2's): ``nav2_msgs/action/NavigateToPose``
  driving the base to a pose (the place at that pose, or a new one);
* ``check/<name>``: ``htn_interfaces/srv/Check`` for every check;
* ``observe``: ``htn_interfaces/srv/GetState``, the facts the robot observes;
* ``pose``: ``geometry_msgs/msg/PoseStamped``, 20 times a second, its stamp the
  simulated clock; ``faults``: ``htn_interfaces/msg/Event``, each fault injected.

The simulation runs at ``speed`` times real time (0: as fast as it can). One
lock serialises everything that touches the simulation: a skill advances it
one tick at a time, and checks, observations and poses are taken between ticks.
"""

from __future__ import annotations

import json
import math
import threading
import time
from dataclasses import dataclass

import rclpy
from geometry_msgs.msg import PoseStamped
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node

from htn.jshop.language.terms import source_atom
from htn.robot.interface import SkillResult

from .interfaces import import_interfaces, import_type
from .shutdown import end_within, spin

NAVIGATE = "/navigate_to_pose"
POSE_HZ = 20.0


@dataclass
class RobotSettings:
    """What ``htn ros robot`` is told."""

    problem: str | None = None  # the world; default: the bundled bring_object problem
    faults: str = ""
    seed: int = 0
    speed: float = 1.0  # times real time; 0: as fast as it can
    namespace: str = "/robot"
    gui: bool = False


class RobotNode(Node):
    """Serves ``robot``'s skills and checks (see the module's docstring)."""

    def __init__(
        self, robot, speed: float = 1.0, namespace: str = "/robot", name: str = "htn_robot_sim"
    ):
        super().__init__(name)
        self.robot, self.speed = robot, speed
        self.ns = namespace.rstrip("/")
        self.types = import_interfaces()
        self._sim = threading.Lock()  # the simulation: one toucher at a time
        self._acting = threading.Lock()  # one skill at a time
        self._faults_sent = 0
        group = ReentrantCallbackGroup()
        t = self.types
        self.skill_servers = [
            ActionServer(
                self,
                t.Skill,
                f"{self.ns}/skill/{name}",
                execute_callback=self._skill_callback(name),
                goal_callback=lambda _: GoalResponse.ACCEPT,
                cancel_callback=lambda _: CancelResponse.ACCEPT,
                callback_group=group,
            )
            for name in sorted(type(robot)._skills)
        ]
        if "move_base" in type(robot)._skills:
            self.skill_servers.append(
                ActionServer(
                    self,
                    import_type("nav2_msgs/action/NavigateToPose"),
                    NAVIGATE,
                    execute_callback=self._navigate,
                    goal_callback=lambda _: GoalResponse.ACCEPT,
                    cancel_callback=lambda _: CancelResponse.ACCEPT,
                    callback_group=group,
                )
            )
        self.check_services = [
            self.create_service(
                t.Check, f"{self.ns}/check/{name}", self._check_callback(name), callback_group=group
            )
            for name in robot.check_names()
        ]
        self.check_services.append(
            self.create_service(
                t.GetState, f"{self.ns}/observe", self._observe, callback_group=group
            )
        )
        self._pose = self.create_publisher(PoseStamped, f"{self.ns}/pose", 10)
        self._faults = self.create_publisher(t.Event, f"{self.ns}/faults", 100)
        self.create_timer(1.0 / POSE_HZ, self._publish_pose, callback_group=group)

    # ------------------------------------------------------------ skills
    def _skill_callback(self, name: str):
        def execute(handle):
            result = self._act(
                handle,
                name,
                tuple(handle.request.args),
                lambda: self.types.Skill.Feedback(sim_t=self.robot.sim_time),
                fails_as_result=True,
            )
            return self.types.Skill.Result(
                ok=result.ok, detail=result.detail, sim_t=self.robot.sim_time
            )

        return execute

    def _navigate(self, handle):
        kind = import_type("nav2_msgs/action/NavigateToPose")
        pose = handle.request.pose.pose
        yaw = 2 * math.atan2(pose.orientation.z, pose.orientation.w)
        place = self._place_at(pose.position.x, pose.position.y, yaw)
        began = self.robot.sim_time

        def feedback():
            x, y, _ = self.robot.base.pose
            fb = kind.Feedback(
                current_pose=self._pose_message(),
                distance_remaining=float(math.hypot(pose.position.x - x, pose.position.y - y)),
            )
            fb.navigation_time.sec = int(self.robot.sim_time - began)
            return fb

        result = self._act(handle, "move_base", (place,), feedback, fails_as_result=False)
        return kind.Result(
            error_code=0 if result.ok else 1, error_msg="" if result.ok else result.detail
        )

    def _place_at(self, x: float, y: float, yaw: float) -> str:
        """The world's place at this pose, or a new one named after it."""
        from htn.robot.world import Place

        places = self.robot.world.places
        for name, p in places.items():
            if (
                math.hypot(p.x - x, p.y - y) < 0.02
                and abs(math.remainder(p.theta - yaw, math.tau)) < 0.02
            ):
                return name
        name = f"pose_{x:.2f}_{y:.2f}_{math.degrees(yaw):.0f}"
        places[name] = Place(name, x, y, yaw)
        return name

    def _act(self, handle, name: str, args: tuple, feedback, fails_as_result: bool) -> SkillResult:
        """Run skill ``name`` to its end, a cancel, or an error, and set the
        goal's state (the caller returns the result message): canceled,
        succeeded, or for a failed skill aborted unless ``fails_as_result``
        (the Skill action's result says ``ok`` itself)."""
        with self._acting:
            with self._sim:
                started = self.robot.act(name, *args)
            result = self._tick(handle, started, feedback)
            self._publish_pose()  # the clock where the skill ended, before its result
            if handle.is_active:
                if handle.is_cancel_requested:
                    handle.canceled()
                elif result.ok or fails_as_result:
                    handle.succeed()
                else:
                    handle.abort()
            return result

    def _tick(self, handle, started, feedback) -> SkillResult:
        if isinstance(started, SkillResult):
            self._send_faults()
            return started
        wall, sim, shown = time.monotonic(), self.robot.sim_time, time.monotonic()
        try:
            while True:
                if handle.is_cancel_requested or not rclpy.ok():
                    with self._sim:
                        started.close()
                        self.robot.hold()
                    self._send_faults()
                    return SkillResult(False, "cancelled: the robot holds its pose")
                with self._sim:
                    for _ in range(self.robot.steps_per_tick):
                        next(started)
                self._send_faults()
                if time.monotonic() - shown > 0.1:
                    handle.publish_feedback(feedback())
                    shown = time.monotonic()
                if self.speed > 0:
                    ahead = (self.robot.sim_time - sim) / self.speed - (time.monotonic() - wall)
                    if ahead > 0:
                        time.sleep(ahead)
        except StopIteration as stop:
            self._send_faults()
            return stop.value
        except Exception as exc:  # a skill's own error: the goal fails, the node lives
            with self._sim:
                self.robot.hold()
            return SkillResult(False, f"internal error: {type(exc).__name__}: {exc}")

    def _send_faults(self) -> None:
        for f in self.robot.injected_faults()[self._faults_sent :]:
            self._faults_sent += 1
            self._faults.publish(
                self.types.Event(
                    t=time.time(),
                    sim_t=float(f["sim_t"]),
                    step=-1,
                    event="fault",
                    detail=f["detail"],
                    record=json.dumps({"kind": f["kind"], **f}),
                )
            )

    # ------------------------------------------------------------ checks, state
    def _check_callback(self, name: str):
        def answer(request, response):
            with self._sim:
                seen = self.robot.check(name, *request.args)
            response.ok, response.detail = bool(seen.ok), seen.detail
            return response

        return answer

    def _observe(self, request, response):
        with self._sim:
            response.facts = [source_atom(p, args) for p, args in self.robot.observe()]
        return response

    def _pose_message(self) -> PoseStamped:
        msg = PoseStamped()
        t = self.robot.sim_time
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int((t % 1) * 1e9)
        msg.header.frame_id = "map"
        x, y, yaw = self.robot.base.pose
        msg.pose.position.x, msg.pose.position.y = float(x), float(y)
        msg.pose.orientation.z, msg.pose.orientation.w = math.sin(yaw / 2), math.cos(yaw / 2)
        return msg

    def _publish_pose(self) -> None:
        self._pose.publish(self._pose_message())


def build_robot(settings: RobotSettings):
    """The PyBullet robot of the settings' problem (the domestic robot, or
    the kitchen robot for a kitchen problem)."""
    from importlib.resources import files

    from htn.jshop.readers.load import load_problem
    from htn.robot import simulated_robot
    from htn.robot.faults import Faults, parse_faults

    path = settings.problem or str(files("htn.problems") / "bring_object.jshop")
    problem = load_problem(path)
    faults = Faults(**parse_faults(settings.faults, Faults.kinds()))
    return simulated_robot(
        problem.instances[0].state, gui=settings.gui, faults=faults, seed=settings.seed
    )


def serve(settings: RobotSettings, name: str = "htn_robot_sim", on_ready=None) -> int:
    """Run the robot node until it is shut down (Ctrl-C, SIGTERM)."""
    robot = build_robot(settings)
    rclpy.init()
    node = RobotNode(robot, settings.speed, settings.namespace, name)
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    if on_ready is not None:
        on_ready(node)
    try:
        spin(executor)
    except KeyboardInterrupt:
        pass
    finally:
        end_within("htn ros robot")
        executor.shutdown(timeout_sec=5.0)
        node.destroy_node()
        robot.close()
        if rclpy.ok():
            rclpy.shutdown()
    return 0
