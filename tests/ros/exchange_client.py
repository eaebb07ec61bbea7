"""The client of test_interfaces.py: finds htn_interfaces itself, in this
process (``import_interfaces``: the cache's build, its libraries preloaded),
sends goals to exchange_server.py, collects their feedback and results, calls
the services, and prints what it got as one JSON object.

Run as ``python exchange_client.py NAME``; every wait has a timeout."""

import json
import sys
import time

import rclpy
from rclpy.action import ActionClient

from htn.ros.interfaces import import_interfaces

t = import_interfaces()

NAME, TIMEOUT = sys.argv[1], 20.0
rclpy.init()
node = rclpy.create_node("client_" + NAME)


def wait(future):
    rclpy.spin_until_future_complete(node, future, timeout_sec=TIMEOUT)
    assert future.done(), "no answer within the timeout"
    return future.result()


def goal(tasks, options="", until=None):
    events = []
    handle = wait(
        client.send_goal_async(
            t.ExecuteTasks.Goal(tasks=tasks, options=options),
            feedback_callback=lambda f: events.append(json.loads(f.feedback.event.record)),
        )
    )
    assert handle.accepted
    if until:
        deadline = time.monotonic() + TIMEOUT
        while len(events) < until and time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.1)
        wait(handle.cancel_goal_async())
    r = wait(handle.get_result_async()).result
    return {
        "outcome": r.outcome,
        "summary": r.summary,
        "error": r.error,
        "plan": list(r.plan),
        "tree": json.loads(r.tree) if r.tree else None,
        "steps": r.steps,
        "verified": r.verified,
        "events": events,
    }


client = ActionClient(node, t.ExecuteTasks, f"/{NAME}/execute")
assert client.wait_for_server(timeout_sec=TIMEOUT), "no action server"
out = {
    "done": goal("((bring jenny pringles))"),
    "cancelled": goal("(bring jenny pringles)", '{"until_cancelled": true}', until=3),
    "refused": goal("bring jenny"),
}
state = node.create_client(t.GetState, f"/{NAME}/state")
update = node.create_client(t.UpdateFacts, f"/{NAME}/update_facts")
assert state.wait_for_service(timeout_sec=TIMEOUT) and update.wait_for_service(timeout_sec=TIMEOUT)
out["before"] = list(wait(state.call_async(t.GetState.Request(pattern="(at ?who ?where)"))).facts)
change = t.Facts(add=["(at jenny kitchen)"], remove=["(at jenny sofa)"], source="test")
answer = wait(update.call_async(t.UpdateFacts.Request(facts=change)))
out["update"] = [answer.ok, answer.error, answer.facts]
out["after"] = list(wait(state.call_async(t.GetState.Request(pattern="(at jenny ?where)"))).facts)
out["all"] = len(wait(state.call_async(t.GetState.Request())).facts)
print(json.dumps(out))
node.destroy_node()
rclpy.try_shutdown()
