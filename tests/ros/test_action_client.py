"""htn's action client (:mod:`htn.ros.action_client`) against rclpy's race
(ros2/rclpy#1123): a goal's answer taken by the spinning thread before the
sending thread has recorded the request is not dropped. Real rclpy in a
process of its own: a server and a client spun in another thread, as
:class:`~htn.ros.robot.RosRobot` spins; each send made slow right after the
request left (as when the sending thread loses the processor there)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

import rosenv

pytestmark = [pytest.mark.slow, pytest.mark.ros]

SCRIPT = textwrap.dedent('''
    import json, sys, threading, time
    import rclpy
    from rclpy.action import ActionClient, ActionServer
    from rclpy.executors import MultiThreadedExecutor, SingleThreadedExecutor
    from htn.ros.action_client import OrderedActionClient
    from htn.ros.interfaces import import_interfaces

    Skill = import_interfaces().Skill
    rclpy.init()
    server = rclpy.create_node("race_server")

    def execute(handle):
        handle.succeed()
        return Skill.Result(ok=True, detail=handle.request.args[0], sim_t=0.0)

    ActionServer(server, Skill, "/race/skill", execute_callback=execute)
    serving = MultiThreadedExecutor(num_threads=2)
    serving.add_node(server)
    threading.Thread(target=serving.spin, daemon=True).start()

    class Slow:
        """The client's handle, its goal, cancel and result requests slow
        to come back after they have gone out."""
        def __init__(self, handle):
            self._handle = handle
        def __getattr__(self, name):
            return getattr(self._handle, name)
        def __enter__(self):
            return self._handle.__enter__()
        def __exit__(self, *exc):
            return self._handle.__exit__(*exc)
        def _slow(self, send, request):
            number = send(request)
            time.sleep(0.1)  # the answer comes meanwhile
            return number
        def send_goal_request(self, request):
            return self._slow(self._handle.send_goal_request, request)
        def send_result_request(self, request):
            return self._slow(self._handle.send_result_request, request)

    node = rclpy.create_node("race_client")
    kind = OrderedActionClient if sys.argv[1] == "ordered" else ActionClient
    client = kind(node, Skill, "/race/skill")
    client._client_handle = Slow(client._client_handle)
    spinning = SingleThreadedExecutor()
    spinning.add_node(node)

    def spin():
        while rclpy.ok():
            spinning.spin_once(timeout_sec=0.05)

    threading.Thread(target=spin, daemon=True).start()
    assert client.wait_for_server(timeout_sec=30)

    def answer(future, wait=10.0):
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        return future.result() if done.wait(wait) else None

    answered = results = 0
    for i in range(5):
        handle = answer(client.send_goal_async(Skill.Goal(args=[f"goal {i}"])))
        if handle is not None and handle.accepted:
            answered += 1
            result = answer(handle.get_result_async())
            results += result is not None and result.result.detail == f"goal {i}"
    print(json.dumps({"answered": answered, "results": results}))
    sys.stdout.flush()
    import os
    os._exit(0)
''')


@pytest.fixture(scope="module")
def ros():
    return rosenv.ready("test_action_client")


def test_every_goal_and_result_answer_reaches_its_request(ros):
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, "ordered"],
        env=ros,
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    assert json.loads(done.stdout.splitlines()[-1]) == {"answered": 5, "results": 5}
    assert "Ignoring unexpected" not in done.stderr
