"""A stand-in for htn's node in plain rclpy, for test_interfaces.py: the
action ``/NAME/execute`` (ExecuteTasks) and the services ``/NAME/state``
(GetState) and ``/NAME/update_facts`` (UpdateFacts) over a set of facts.

Run as ``python exchange_server.py NAME`` with htn_interfaces reachable
through the environment (PYTHONPATH, LD_LIBRARY_PATH: what
``htn.ros.interfaces.activate`` returns); serves until SIGINT."""

import json
import sys
import time

import rclpy
from htn_interfaces.action import ExecuteTasks
from htn_interfaces.msg import Event
from htn_interfaces.srv import GetState, UpdateFacts
from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor

NAME = sys.argv[1]
facts = {"(at robby kitchen)", "(at jenny sofa)", "(holding robby nothing)"}
PLAN = ["(!walk robby kitchen sofa)", "(!give robby jenny pringles)"]


def matches(pattern, fact):
    p, f = pattern.strip("()").split(), fact.strip("()").split()
    return len(p) == len(f) and all(a.startswith("?") or a == b for a, b in zip(p, f))


def event(step, kind):
    record = {
        "t": time.time(),
        "sim_t": 0.5 * step,
        "step": step,
        "action": PLAN[step % 2],
        "event": kind,
        "attempt": 1,
    }
    return ExecuteTasks.Feedback(
        event=Event(
            t=record["t"],
            sim_t=record["sim_t"],
            step=step,
            action=record["action"],
            event=kind,
            attempt=1,
            detail="",
            record=json.dumps(record),
        )
    )


def execute(goal):
    tasks, options = goal.request.tasks, json.loads(goal.request.options or "{}")
    if not tasks.startswith("("):
        goal.succeed()
        return ExecuteTasks.Result(
            outcome="refused", summary="refused", error="<goal>:1:1: a task list starts with '('"
        )
    if options.get("until_cancelled"):  # events until the client has seen enough
        step = 0
        while not goal.is_cancel_requested:
            goal.publish_feedback(event(step, "started"))
            step += 1
            time.sleep(0.02)  # the pace of a (fake) robot
        goal.canceled()
        return ExecuteTasks.Result(outcome="preempted", summary="preempted", steps=step)
    for step in range(len(PLAN)):
        for kind in ("started", "succeeded"):
            goal.publish_feedback(event(step, kind))
    goal.succeed()
    tree = {"task": tasks, "children": [{"action": a} for a in PLAN]}
    return ExecuteTasks.Result(
        outcome="verified",
        summary="verified: 2 of 2 steps",
        plan=PLAN,
        tree=json.dumps(tree),
        steps=2,
        verified=2,
    )


def state(request, response):
    response.facts = sorted(f for f in facts if not request.pattern or matches(request.pattern, f))
    return response


def update(request, response):
    facts.difference_update(request.facts.remove)
    facts.update(request.facts.add)
    response.ok, response.facts = True, len(facts)
    return response


from htn.ros.shutdown import end_within  # noqa: E402

rclpy.init()
node = rclpy.create_node("server_" + NAME)
group = ReentrantCallbackGroup()
ActionServer(
    node,
    ExecuteTasks,
    f"/{NAME}/execute",
    execute,
    callback_group=group,
    cancel_callback=lambda goal: CancelResponse.ACCEPT,
)
node.create_service(GetState, f"/{NAME}/state", state, callback_group=group)
node.create_service(UpdateFacts, f"/{NAME}/update_facts", update, callback_group=group)
executor = MultiThreadedExecutor()
executor.add_node(node)
try:
    executor.spin()
except (KeyboardInterrupt, ExternalShutdownException):
    pass
finally:
    end_within("exchange_server")  # rclpy's threads may stall the interpreter's exit
    executor.shutdown(timeout_sec=5.0)
    node.destroy_node()
    rclpy.try_shutdown()
