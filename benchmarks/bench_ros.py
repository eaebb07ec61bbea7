"""What the ROS 2 node adds to a run (issue 36): median and max over N goals.

* goal sent -> first action started (the ``start`` event on ``~/events``),
  and that less the planning time (the ``~/plan`` service's round trip for
  the same goal just before, its second call: the first warms the parser);
* event -> received: an event's log time against its arrival at the client
  (the node's log clock starts with the goal's log, so this is the arrival
  delay of the first event, ``header``, against the goal's acceptance);
* cancel sent -> the robot holding (the ``interrupted`` event, which the
  dispatcher emits after ``robot.hold()``), on the PyBullet robot;
* a whole goal's wall time through ROS (sent to result) against the same
  goal in one process (planned, then run on a robot built beforehand, as the
  node's is): the overhead of the node and the middleware.

Run: ``python benchmarks/bench_ros.py [--runs 20] [--robot pybullet]``
(the ros and sim extras; a ROS domain id of its own).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GOAL = "((bring_object jenny pringles guest))"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--robot", default="pybullet")
    args = ap.parse_args()
    os.environ.setdefault("ROS_DOMAIN_ID", "93")
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    import htn
    import rclpy
    from rclpy.action import ActionClient

    from htn.ros.interfaces import import_interfaces
    T = import_interfaces()
    domain, problem = ROOT / "domains" / "domestic.jshop", ROOT / "problems" / "bring_object.jshop"
    rclpy.init()
    client = rclpy.create_node("bench_ros")
    events: list = []
    client.create_subscription(T.Event, "/htn/events",
                               lambda m: events.append((time.perf_counter(), m.event)), 1000)
    action = ActionClient(client, T.ExecuteTasks, "/htn/execute")
    plan_srv = client.create_client(T.PlanTasks, "/htn/plan")
    figures: dict = {"goal sent to first action started (ms)": [],
                     "first action beyond planning (ms)": [], "plan service (ms)": [],
                     "cancel to holding (ms)": [], "goal via ROS (s)": [], "htn.run (s)": []}

    def node():
        return subprocess.Popen([sys.executable, "-m", "htn", "ros", "node", str(domain),
                                 "--problem", str(problem), "--robot", args.robot],
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

    def wait_for(kind: str, since: int, limit: float = 60.0) -> float:
        end = time.perf_counter() + limit
        while time.perf_counter() < end:
            rclpy.spin_once(client, timeout_sec=0.002)
            for at, ev in events[since:]:
                if ev == kind:
                    return at
        raise RuntimeError(f"no {kind} event within {limit} s")

    def goal(cancel_at_start: bool = False) -> None:
        request = T.PlanTasks.Request(tasks=GOAL)
        for _ in range(2):      # the second call: the node's first planning warms its parser
            t0 = time.perf_counter()
            future = plan_srv.call_async(request)
            rclpy.spin_until_future_complete(client, future)
            planning = time.perf_counter() - t0
        since = len(events)
        t1 = time.perf_counter()
        sent = action.send_goal_async(T.ExecuteTasks.Goal(tasks=GOAL))
        rclpy.spin_until_future_complete(client, sent)
        started = wait_for("start", since)
        figures["plan service (ms)"].append(planning * 1e3)
        figures["goal sent to first action started (ms)"].append((started - t1) * 1e3)
        figures["first action beyond planning (ms)"].append((started - t1 - planning) * 1e3)
        if cancel_at_start:
            wait_for("start", since + 1 + [e for _, e in events[since:]].index("start"))
            t2 = time.perf_counter()
            sent.result().cancel_goal_async()
            held = wait_for("interrupted", since)
            figures["cancel to holding (ms)"].append((held - t2) * 1e3)
        done = sent.result().get_result_async()
        rclpy.spin_until_future_complete(client, done)
        if not cancel_at_start:
            figures["goal via ROS (s)"].append(time.perf_counter() - t1)

    for i in range(args.runs):
        for cancel in (False, True):
            proc = node()       # a fresh node and robot: the same start each time
            try:
                assert action.wait_for_server(timeout_sec=30) and plan_srv.wait_for_service(30)
                end = time.perf_counter() + 10     # the events topic, matched both ways
                while client.count_publishers("/htn/events") == 0 and time.perf_counter() < end:
                    rclpy.spin_once(client, timeout_sec=0.01)
                time.sleep(0.5)
                goal(cancel_at_start=cancel)
            finally:
                proc.send_signal(2)
                proc.wait(30)
        # the same goal in one process: planned and run, the robot built
        # beforehand (as the node builds it when it is configured)
        from htn.api.run import prepare
        plan = next(iter(htn.plan(domain, problem)))
        with prepare(plan, robot=args.robot, domain=domain, problem=problem) as execution:
            t0 = time.perf_counter()
            next(iter(htn.plan(domain, problem)))
            execution.begin()
            execution.execute()
            figures["htn.run (s)"].append(time.perf_counter() - t0)
        print(f"run {i + 1}/{args.runs}", file=sys.stderr)
    out = {k: {"median": round(statistics.median(v), 3), "max": round(max(v), 3), "n": len(v)}
           for k, v in figures.items() if v}
    ros_s, run_s = out["goal via ROS (s)"]["median"], out["htn.run (s)"]["median"]
    out["overhead of ROS (s, medians)"] = round(ros_s - run_s, 3)
    print(json.dumps(out, indent=1))
    client.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
