"""Whose turn it is (htn.ros.goals, no ROS in it): goals served one at a
time on an agent, each in its own thread as the node's action server runs
them; a newer goal preempting the running one, which with ``resume`` waits
and goes on after it, newest first; not after a newer goal that failed; a
cancel ending only its own goal."""

from __future__ import annotations

import threading
from types import SimpleNamespace

from htn.api.agent import Agent
from htn.ros.goals import Turns

from conftest import ROOT

DOMAIN = ROOT / "domains" / "domestic.jshop"
PROBLEM = ROOT / "problems" / "bring_object.jshop"
PRINGLES = "((bring_object jenny pringles guest))"
COKE = "((bring_object jenny coke guest))"


class Handle:
    """What the node's goal handle gives: the request's tasks, and whether
    its client asked to cancel it."""

    def __init__(self, name: str, tasks: str):
        self.name = name
        self.request = SimpleNamespace(tasks=tasks)
        self.is_cancel_requested = False


class Watched(Agent):
    """An agent that says when it has been asked to preempt a goal."""

    def __init__(self):
        super().__init__(DOMAIN, PROBLEM, robot="symbolic")
        self.asked = threading.Event()

    def preempt(self, *args, **kwargs):
        try:
            return super().preempt(*args, **kwargs)
        finally:
            self.asked.set()


class Node:
    """Goals served as the node serves them: each in a thread of its own,
    every event recorded ``(goal, event, step)``; ``hooks[(goal, event,
    step)]`` runs in the goal's thread when that event comes."""

    def __init__(self, resume: bool = True):
        self.agent = Watched()
        self.turns = Turns(self.agent, "preempt", resume, None, self.emit)
        self.events: list = []
        self.hooks: dict = {}
        self.results: dict = {}
        self.threads: list = []

    def emit(self, handle, rec) -> None:
        key = (handle.name, rec["event"], rec.get("step"))
        self.events.append(key)
        hook = self.hooks.pop(key, None)
        if hook is not None:
            hook()

    def send(self, handle: Handle) -> None:
        """Serve ``handle`` in a thread of its own."""

        def serve():
            self.results[handle.name] = self.turns.serve(handle)

        thread = threading.Thread(target=serve)
        self.threads.append(thread)
        thread.start()

    def preempting(self, handle: Handle):
        """A hook: send ``handle``, and go on once it has preempted the goal."""

        def hook():
            self.agent.asked.clear()
            self.send(handle)
            assert self.agent.asked.wait(10)

        return hook

    def join(self) -> dict:
        while self.threads:
            self.threads.pop(0).join(30)
        return self.results


def test_a_preempted_goal_resumes_after_the_newer_one_and_both_end_verified():
    node = Node()
    node.hooks[("a", "verified", 3)] = node.preempting(Handle("b", COKE))
    node.send(Handle("a", PRINGLES))
    results = node.join()
    a, b = results["a"], results["b"]
    assert b.outcome == "verified" and b.resumed == 0
    assert a.outcome == "verified" and a.resumed == 1 and a.verified == a.steps == 3 + 8
    assert a.summary.endswith("resumed after a preemption, 3 steps verified before")
    # a waits while b runs, then goes on (a new run: its header)
    waiting = node.events.index(("a", "waiting", None))
    assert node.events[waiting - 1] == ("a", "summary", None)
    assert node.events[waiting + 1] == ("b", "header", None)
    assert node.events[-2:] == [("a", "verified", 8), ("a", "summary", None)]
    assert node.agent.world.query("(has guest ?what)") == [
        "(has guest coke)",
        "(has guest pringles)",
    ]


def test_goals_preempted_in_turn_resume_newest_first():
    node = Node()
    drive = "((go_to jenny entrance))"
    node.hooks[("a", "verified", 3)] = node.preempting(Handle("b", COKE))
    node.hooks[("b", "verified", 2)] = node.preempting(Handle("c", drive))
    node.send(Handle("a", PRINGLES))
    results = node.join()
    assert {k: r.outcome for k, r in results.items()} == dict.fromkeys("abc", "verified")
    headers = [goal for goal, event, _ in node.events if event == "header"]
    assert headers == ["a", "b", "c", "b", "a"]


def test_waiting_goals_end_preempted_after_a_newer_goal_that_failed():
    node = Node()

    def failing():  # the robot's next action fails (a driver error)
        node.agent.robot.fail_fault = 1.0

    node.hooks[("a", "verified", 3)] = node.preempting(Handle("b", COKE))
    node.hooks[("b", "header", None)] = failing
    node.send(Handle("a", PRINGLES))
    results = node.join()
    assert results["b"].outcome == "failed"
    a = results["a"]
    assert a.outcome == "preempted" and a.verified == 3
    assert a.summary.endswith("; not resumed: the goal after it ended failed")
    assert [goal for goal, event, _ in node.events if event == "header"] == ["a", "b"]


def test_a_goal_cancelled_while_it_waits_ends_and_the_running_one_goes_on():
    node = Node()
    a = Handle("a", PRINGLES)

    def cancel_a():
        a.is_cancel_requested = True
        node.turns.cancel(a)

    node.hooks[("a", "verified", 3)] = node.preempting(Handle("b", COKE))
    node.hooks[("b", "verified", 2)] = cancel_a
    node.send(a)
    results = node.join()
    assert results["b"].outcome == "verified"
    assert results["a"].outcome == "preempted"
    assert results["a"].summary.endswith(
        "; not resumed: cancelled by the client while it waited to resume"
    )


def test_without_resume_a_preempted_goal_ends_preempted():
    node = Node(resume=False)
    node.hooks[("a", "verified", 3)] = node.preempting(Handle("b", COKE))
    node.send(Handle("a", PRINGLES))
    results = node.join()
    assert results["a"].outcome == "preempted" and results["a"].verified == 3
    assert results["a"].summary.startswith("preempted: 3 of 8 steps verified")
    assert results["b"].outcome == "verified"
    assert ("a", "waiting", None) not in node.events
