"""htn's planning-and-execution node (htn.ros.node) as a real process, and a
plain rclpy client written here (not htn's) in another: goals planned from
the world model and run, refused with the located reason, the world model
queried and updated. Skipped without the ros extra."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import pytest

import rosenv
from conftest import ROOT

pytestmark = [pytest.mark.slow, pytest.mark.ros]

GOAL = "((bring_object jenny pringles guest))"


@pytest.fixture(scope="module")
def ros():
    return rosenv.ready("test_node")


NODE = textwrap.dedent("""
    import sys
    from htn.ros.node import NodeSettings, serve
    domain, problem, robot, log_dir, resume = sys.argv[1:6]
    sys.exit(serve(NodeSettings(domain, problem, robot=robot, log_dir=log_dir or None,
                                resume=resume == "resume")))
""")

CLIENT = textwrap.dedent('''
    """A plain rclpy client: each line of stdin a request, each answer a JSON line."""
    import json, sys
    import rclpy
    from rclpy.action import ActionClient
    from htn.ros.interfaces import import_interfaces

    T = import_interfaces()
    rclpy.init()
    node = rclpy.create_node("test_client")
    action = ActionClient(node, T.ExecuteTasks, "/htn/execute")
    state = node.create_client(T.GetState, "/htn/state")
    update = node.create_client(T.UpdateFacts, "/htn/update_facts")
    plan = node.create_client(T.PlanTasks, "/htn/plan")
    events = []
    node.create_subscription(T.Event, "/htn/events", lambda m: events.append(m.event), 100)
    assert action.wait_for_server(timeout_sec=30), "the node's action server never came"
    for c in (state, update, plan):
        assert c.wait_for_service(timeout_sec=30)

    def call(client, request):
        future = client.call_async(request)
        rclpy.spin_until_future_complete(node, future, timeout_sec=30)
        return future.result()

    def ended(sent):
        done = sent.result().get_result_async()
        rclpy.spin_until_future_complete(node, done, timeout_sec=120)
        r = done.result().result
        return dict(outcome=r.outcome, summary=r.summary, error=r.error, plan=list(r.plan),
                    steps=r.steps, verified=r.verified, status=done.result().status)

    for line in sys.stdin:
        kind, _, text = line.rstrip("\\n").partition(" ")
        if kind == "cancel":        # cancel once the second action has started
            since = len(events)
            sent = action.send_goal_async(T.ExecuteTasks.Goal(tasks=text))
            rclpy.spin_until_future_complete(node, sent, timeout_sec=30)
            while events[since:].count("start") < 2:
                rclpy.spin_once(node, timeout_sec=0.005)
            canceling = sent.result().cancel_goal_async()
            rclpy.spin_until_future_complete(node, canceling, timeout_sec=30)
            done = sent.result().get_result_async()
            rclpy.spin_until_future_complete(node, done, timeout_sec=60)
            r = done.result().result
            out = dict(outcome=r.outcome, summary=r.summary, status=done.result().status,
                       cancelling=len(canceling.result().goals_canceling))
        elif kind == "preempt":     # FIRST || SECOND: the second once the first's 2nd action runs
            first, second = text.split(" || ")
            since = len(events)
            sent = action.send_goal_async(T.ExecuteTasks.Goal(tasks=first))
            rclpy.spin_until_future_complete(node, sent, timeout_sec=30)
            while events[since:].count("start") < 2:
                rclpy.spin_once(node, timeout_sec=0.005)
            newer = action.send_goal_async(T.ExecuteTasks.Goal(tasks=second))
            rclpy.spin_until_future_complete(node, newer, timeout_sec=30)
            out = dict(first=ended(sent), second=ended(newer), events=events[since:])
        elif kind == "execute":
            feedback = []
            sent = action.send_goal_async(T.ExecuteTasks.Goal(tasks=text),
                                          feedback_callback=lambda m: feedback.append(m.feedback.event.event))
            rclpy.spin_until_future_complete(node, sent, timeout_sec=30)
            done = sent.result().get_result_async()
            rclpy.spin_until_future_complete(node, done, timeout_sec=60)
            r = done.result().result
            out = dict(outcome=r.outcome, summary=r.summary, error=r.error, plan=list(r.plan),
                       steps=r.steps, verified=r.verified, tree=bool(r.tree),
                       status=done.result().status, feedback=feedback)
        elif kind == "state":
            out = dict(facts=list(call(state, T.GetState.Request(pattern=text)).facts))
        elif kind == "plan":
            r = call(plan, T.PlanTasks.Request(tasks=text))
            out = dict(ok=r.ok, error=r.error, steps=list(r.steps), cost=r.cost)
        else:
            add, delete = json.loads(text)
            r = call(update, T.UpdateFacts.Request(facts=T.Facts(add=add, remove=delete,
                                                                 source="camera")))
            out = dict(ok=r.ok, error=r.error, facts=r.facts)
        print(json.dumps(out), flush=True)
    node.destroy_node()
    rclpy.shutdown()
''')


def talk(
    env, requests: list[str], robot: str = "symbolic", log_dir: str = "", resume: bool = False
) -> list[dict]:
    """Start the node on the domestic domain and bring_object, send
    ``requests`` from a client process, stop the node; the answers."""
    node = subprocess.Popen(
        [
            sys.executable,
            "-c",
            NODE,
            str(ROOT / "domains" / "domestic.jshop"),
            str(ROOT / "problems" / "bring_object.jshop"),
            robot,
            log_dir,
            "resume" if resume else "",
        ],
        env=env,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        client = subprocess.run(
            [sys.executable, "-c", CLIENT],
            input="\n".join(requests) + "\n",
            env=env,
            capture_output=True,
            text=True,
            timeout=240,
        )
    finally:
        node.send_signal(2)
        try:
            out, err = node.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            node.kill()
            out, err = node.communicate()
    assert client.returncode == 0, client.stderr[-3000:] + err[-2000:]
    assert node.returncode == 0 and "Traceback" not in err, err[-3000:]
    return [json.loads(line) for line in client.stdout.splitlines()]


def test_goals_through_ros_end_as_htn_run_and_the_world_model_keeps_what_they_did(ros):
    import htn

    domain, problem = ROOT / "domains" / "domestic.jshop", ROOT / "problems" / "bring_object.jshop"
    alone = htn.run(
        next(iter(htn.plan(domain, problem))), robot="symbolic", domain=domain, problem=problem
    )
    answers = talk(
        ros,
        [
            f"plan {GOAL}",
            f"execute {GOAL}",
            "execute ((fly_to jenny moon))",
            "execute ((bring_object jenny pringles))",
            "execute ((bring_object jenny pringles guest)",
            "state (has ?who ?what)",
            f"execute {GOAL}",
        ],
    )
    planned, done, unknown, arity, syntax, state, again = answers
    assert planned["ok"] and len(planned["steps"]) == 8
    assert done["outcome"] == "verified" and done["status"] == 4  # SUCCEEDED
    assert done["plan"] == alone.plan and done["verified"] == done["steps"] == 8
    assert done["summary"] == alone.summary.line() and done["tree"]
    # feedback as it happens, in the run's order: the action client may miss
    # what comes before its feedback subscription is matched and after the
    # result (the complete stream is ~/events, which htn ros send reads)
    logged = iter([e["event"] for e in alone.events])
    assert done["feedback"] and all(name in logged for name in done["feedback"])
    assert unknown["outcome"] == "refused" and unknown["status"] == 6  # ABORTED
    assert unknown["error"].startswith("goal:1:3: unknown task 'fly_to'")
    assert arity["error"].startswith("goal:1:3: 'bring_object' takes 3 arguments, given 2")
    assert (
        syntax["outcome"] == "refused" and syntax["error"] == "goal:1:1: this '(' is never closed"
    )
    assert state["facts"] == ["(has guest pringles)"]
    # planned from the world model: the pringles were handed over already
    assert again["outcome"] == "refused" and "no plan" in again["error"]


def test_facts_from_another_node_change_the_next_plan_and_bad_ones_are_refused(ros):
    answers = talk(
        ros,
        [
            'facts [["(flies jenny)"], []]',
            'facts [["(robot_at jenny counter_front)"], ["(robot_at jenny home_base)"]]',
            f"plan {GOAL}",
        ],
    )
    bad, good, planned = answers
    assert not bad["ok"] and bad["error"].startswith("camera:1:1: unknown predicate 'flies'")
    assert good["ok"] and good["facts"] == bad["facts"]
    assert planned["ok"] and len(planned["steps"]) == 7  # no drive to the counter


def test_htn_ros_send_prints_the_steps_and_exits_as_htn_run(ros, tmp_path):
    node = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "htn",
            "ros",
            "node",
            str(ROOT / "domains" / "domestic.jshop"),
            "--problem",
            str(ROOT / "problems" / "bring_object.jshop"),
            "--robot",
            "symbolic",
        ],
        env=ros,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:

        def send(*args):
            return subprocess.run(
                [sys.executable, "-m", "htn", "ros", "send", *args],
                env=ros,
                cwd=ROOT,
                capture_output=True,
                text=True,
                timeout=120,
            )

        done = send("--from-problem", "problems/bring_object.jshop")
        refused = send("((fly_to jenny moon))")
    finally:
        node.send_signal(2)
        node.communicate(timeout=30)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert [ln.split()[1] for ln in lines[:-1]] == ["verified"] * 8
    assert lines[-1] == "verified: 8 of 8 steps verified, 0 retries, 0 replans, 8.0 s simulated"
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    assert refused.stderr.strip().endswith(
        "goal:1:3: unknown task 'fly_to': the domain has no method for it"
    )


@pytest.mark.sim
def test_a_cancelled_goal_on_the_pybullet_robot_ends_preempted_and_the_robot_holds(ros, tmp_path):
    pytest.importorskip("pybullet", reason="the sim extra is not installed")
    cancelled, again = talk(
        ros, [f"cancel {GOAL}", f"execute {GOAL}"], robot="pybullet", log_dir=str(tmp_path)
    )
    assert cancelled["cancelling"] == 1 and cancelled["status"] == 5  # CANCELED
    assert cancelled["outcome"] == "preempted", cancelled
    assert cancelled["summary"].startswith("preempted: 1 of 8 steps verified"), cancelled
    log = [json.loads(line) for line in (tmp_path / "goal-0001.jsonl").read_text().splitlines()]
    interrupted = [e for e in log if e["event"] == "interrupted"]
    assert len(interrupted) == 1 and "cancelled by the client" in interrupted[0]["detail"]
    assert "the robot holds its pose" in interrupted[0]["detail"]
    assert interrupted[0]["step"] == 2 and log[-1]["event"] == "summary"
    assert interrupted[0]["sim_t"] == log[-1]["sim_t"]  # nothing ran after the cancel
    # the same goal again is planned from where the robot stopped (mid-drive:
    # its pose is no location, so the plan drives on from the one it left)
    assert again["outcome"] == "verified", again


def events_of(path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.mark.sim
def test_a_newer_goal_preempts_and_with_resume_both_goals_end_verified(ros, tmp_path):
    """Issue 36's acceptance: the first goal, preempted by a second one,
    resumes after it from the observed state, its done steps staying done.
    First, the second goal starts with the drive running now: the drive goes
    on and the second goal takes it as its first step, verified; then one
    that does not: the first goal halts mid-drive."""
    pytest.importorskip("pybullet", reason="the sim extra is not installed")
    went_on, halted = talk(
        ros,
        [
            f"preempt {GOAL} || ((go_to jenny counter_front))",
            ("preempt ((bring_object jenny coke guest)) || ((go_to jenny entrance))"),
        ],
        robot="pybullet",
        log_dir=str(tmp_path),
        resume=True,
    )
    first, second = went_on["first"], went_on["second"]
    assert second["outcome"] == "verified" and second["status"] == 4, second
    assert second["plan"] == ["(!move_base jenny home_base counter_front)"]
    assert first["outcome"] == "verified" and first["status"] == 4, first
    assert first["summary"].endswith("; resumed after a preemption, 2 steps verified before")
    assert first["plan"][:2] == [
        "(!say jenny task_accepted)",
        "(!move_base jenny home_base counter_front)",
    ]
    # re-planned from the counter, where the drive the second goal took over ended
    assert first["plan"][2:4] == [
        "(!say jenny task_accepted)",
        "(!detect_object jenny pringles kitchen_counter)",
    ]
    assert first["verified"] == first["steps"] == 2 + 7
    assert went_on["events"].count("waiting") == 1
    # the logs: the first run preempted, the second's drive adopted, the first resumed
    log = events_of(tmp_path / "goal-0001.jsonl")
    assert [e["step"] for e in log if e["event"] == "start"] == [1, 2]  # the drive once
    assert log[-1]["result"] == "preempted" and log[-1]["reason"] == "preempted by a newer goal"
    assert log[-2]["event"] == "interrupted" and log[-2]["step"] is None  # after the drive
    log = events_of(tmp_path / "goal-0002.jsonl")
    assert [(e["event"], e.get("adopted")) for e in log if e["step"] == 1] == [("verified", True)]
    log = events_of(tmp_path / "goal-0001-resumed-1.jsonl")
    assert log[-1]["result"] == "verified" and log[-1]["resumed"]["verified_before"] == 2

    first, second = halted["first"], halted["second"]
    assert second["outcome"] == "verified" and second["plan"] == [
        "(!move_base jenny sofa_front entrance)"
    ], second
    assert first["outcome"] == "verified", first
    assert "resumed after a preemption, 1 step verified before" in first["summary"]
    assert first["plan"][1:3] == [
        "(!say jenny task_accepted)",
        "(!move_base jenny entrance dining_front)",
    ]
    log = events_of(tmp_path / "goal-0003.jsonl")
    assert log[-2]["event"] == "interrupted" and log[-2]["step"] == 2  # mid-drive
    assert log[-2]["detail"] == "preempted by a newer goal; the robot holds its pose"
    assert log[-1]["result"] == "preempted"
    assert events_of(tmp_path / "goal-0003-resumed-1.jsonl")[-1]["result"] == "verified"
