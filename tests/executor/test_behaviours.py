"""The executor's behaviour tree ticked in this process against a scripted robot.

The task dispatcher (:mod:`htn.executor.dispatcher`) builds the real tree
(:mod:`htn.executor.task_bt`, :mod:`htn.executor.behaviours`) from a plan the
real planner finds for a small domain; what is scripted is the environment
only, as py_trees' own tests script the children of the composite they test:
:class:`ScriptedRobot` is an implementation of the robot interface whose
skills run for a given number of physics steps and end as told, and whose
checks answer as told, call by call. The robot records what the tree made
it do (each physics step, each check, each preemption and hold), so the
tests see the life cycle tick by tick: execute with its hold-monitors beside
it, then the monitor; each outcome (finished, verified, failed, aborted,
retrying); retries up to the operator's limit; a hold-monitor that breaks
mid-action preempting the skill; a halt between ticks; and a repair grafted
into the tree from what the robot observes of a symbolic world.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import pytest
from py_trees.common import Status

from htn.executor.dispatcher import TaskDispatcher
from htn.executor.log import EventLog
from htn.executor.machines.base import ActionMachine, action
from htn.executor.task_bt import actions
from htn.jshop import Planner
from htn.jshop.readers.load import parse_text
from htn.robot.interface import Check, Robot, SkillResult, check, skill

DOMAIN = """(defdomain scripted (
  (:operator (!pick ?o) ((on ?o table)) ((on ?o table)) ((holding ?o)))
  (:operator (!lift ?o) ((on ?o floor)) ((on ?o floor)) ((holding ?o)))
  (:operator (!place ?o) ((holding ?o)) ((holding ?o)) ((on ?o shelf)))
  (:operator (!!tally ?o) () () ((tallied ?o)))
  (:method (shelve ?o)
    ((on ?o floor)) ((!lift ?o) (!place ?o) (!!tally ?o))
    ((on ?o table)) ((!pick ?o) (!place ?o) (!!tally ?o)))
  (:method (tidy ?a ?b) () ((shelve ?a) (shelve ?b)))))"""
PROBLEM = "(defproblem room scripted ((on cup table) (on book table)) ((tidy cup book)))"
PLAN = [
    "(!pick cup)",
    "(!place cup)",
    "(!!tally cup)",
    "(!pick book)",
    "(!place book)",
    "(!!tally book)",
]
DT = 0.1  # simulated seconds per physics step


# ------------------------------------------------------------------ the scripted robot


@dataclass
class Run:
    """A scripted skill call: ``steps`` physics steps (0: it ends at once,
    as on an instantaneous robot), then ``ok`` (the robot's own belief)."""

    steps: int = 2
    ok: bool = True
    detail: str = ""


class ScriptedRobot(Robot):
    """Skills ``pick``, ``lift``, ``place`` and checks ``holding``, ``on_shelf``
    (monitors) and ``arm_clear`` (a hold-monitor), each answering from its
    script: the n-th call of a skill plays ``skills[name][n]``, the n-th call
    of a check returns ``checks[name][n]`` (a bool, or a function of the
    robot for an answer that depends on where the run is); the last entry
    repeats. ``world`` is what ``observe`` reports of the dynamic predicates."""

    steps_per_tick = 1

    def __init__(self, skills=None, checks=None, world=()):
        self.skills = skills or {}
        self.checks = checks or {}
        self.world = list(world)
        self.calls = defaultdict(int)
        self.trace: list[tuple] = []  # what the tree made the robot do, in order
        self.steps = 0  # physics steps, all skills
        self.sim_time = 0.0
        self.on_step = None  # called after each physics step (a test's hook)

    def _scripted(self, table, name):
        script = table.get(name, [])
        n = self.calls[name]
        self.calls[name] += 1
        return script[min(n, len(script) - 1)] if script else None

    def _play(self, name, obj):
        run = self._scripted(self.skills, name) or Run()
        self.trace.append(("start", name, obj))
        if run.steps == 0:
            return SkillResult(run.ok, run.detail or f"{name} {obj}")
        return self._ticking(name, obj, run)

    def _ticking(self, name, obj, run):
        # as the PyBullet robots' skills: each next() runs one physics step
        done = 0
        try:
            while done < run.steps:
                done += 1
                self.steps += 1
                self.sim_time = round(self.sim_time + DT, 6)
                self.trace.append(("step", name, done))
                if self.on_step:
                    self.on_step(self)
                yield
        finally:
            if done < run.steps:
                self.trace.append(("preempted", name, done))
        return SkillResult(run.ok, run.detail or f"{name} {obj}")

    def _answer(self, name, *args) -> Check:
        answer = self._scripted(self.checks, name)
        ok = True if answer is None else answer(self) if callable(answer) else answer
        self.trace.append(("check", name, *args, ok))
        return Check(ok, f"{name} {' '.join(args)}: {'yes' if ok else 'no'}")

    @skill("pick")
    def pick(self, obj):
        return self._play("pick", obj)

    @skill("lift")
    def lift(self, obj):
        return self._play("lift", obj)

    @skill("place")
    def place(self, obj):
        return self._play("place", obj)

    @check("holding")
    def check_holding(self, obj):
        return self._answer("holding", obj)

    @check("on_shelf")
    def check_on_shelf(self, obj):
        return self._answer("on_shelf", obj)

    @check("arm_clear")
    def check_arm_clear(self):
        return self._answer("arm_clear")

    def hold(self):
        self.trace.append(("hold",))

    def observe(self):
        return self.world


# the action state machines of the scripted domain, registered as a plugin would
@action("!pick", domain="scripted")
class Pick(ActionMachine):
    def execute(self, robot, obj):
        return robot.act("pick", obj)

    def monitor(self, robot, obj):
        return robot.check("holding", obj)

    def holds(self, robot, obj):
        return [("the arm is clear", lambda: robot.check("arm_clear"))]


@action("!lift", domain="scripted")
class Lift(Pick):
    def execute(self, robot, obj):
        return robot.act("lift", obj)


@action("!place", domain="scripted")
class Place(ActionMachine):
    def execute(self, robot, obj):
        return robot.act("place", obj)

    def monitor(self, robot, obj):
        return robot.check("on_shelf", obj)


# ------------------------------------------------------------------ helpers


@pytest.fixture(scope="module")
def model():
    domain, problem = parse_text(DOMAIN, "scripted.jshop"), parse_text(PROBLEM, "room.jshop")
    instance = problem.instances[0]
    plan = next(Planner(domain, instance, record_trees=True).plans())
    assert plan.lines() == PLAN
    return domain, instance, plan


def dispatcher(model, robot, retries=None, replan=False):
    domain, instance, plan = model
    log = EventLog(None, clock=lambda: robot.sim_time)
    return TaskDispatcher(
        robot, domain, instance, plan.steps, retries or {}, log, replan=replan, tree=plan.tree
    )


def events(d, *kinds):
    """(step, action, event, attempt) of the log's events (of ``kinds`` only)."""
    return [
        (e["step"], e["action"], e["event"], e["attempt"])
        for e in d.log.events
        if not kinds or e["event"] in kinds
    ]


def of_action(d, text):
    return [(e["event"], e["attempt"]) for e in d.log.events if e["action"] == text]


def behaviour(d, text, name):
    """The behaviour called ``name`` in the subtree of the plan step ``text``."""
    top = next(
        b
        for b in d.root.iterate()
        if getattr(b, "htn_action", None) is not None and b.htn_action.text == text
    )
    return next(b for b in top.iterate() if b.name == name)


# ------------------------------------------------------------------ the tree


def test_the_behaviour_tree_has_the_task_tree_shape(model):
    d = dispatcher(model, ScriptedRobot())
    root = d.root
    assert [c.name for c in root.children] == ["tidy"]
    # compound tasks are sequences named by their node path (the paper's)
    assert [c.name for c in root.children[0].children] == [
        "tidy/shelve :call 1",
        "tidy/shelve :call 2",
    ]
    pick = next(b for b in root.iterate() if getattr(b, "htn_action", None) is not None)
    # Report > RetryAborted > Sequence(attempt) > [Parallel(execute | hold), monitor]
    assert pick.name == "(!pick cup)" and pick.decorated.name == "retry <= 0"
    attempt = pick.decorated.decorated
    assert [c.name for c in attempt.children] == ["execute | hold", "monitor"]
    assert [c.name for c in attempt.children[0].children] == ["execute", "the arm is clear"]
    # the internal operator is one behaviour; place has no hold-monitor
    assert [a.text for a in actions(root)] == PLAN
    assert behaviour(d, "(!!tally cup)", "(!!tally cup)").children == []
    assert [c.name for c in behaviour(d, "(!place cup)", "attempt").children] == [
        "execute",
        "monitor",
    ]


# ------------------------------------------------------------------ life cycle


def test_execute_ticks_the_skill_with_its_hold_monitor_then_the_monitor_verifies(model):
    robot = ScriptedRobot(skills={"pick": [Run(steps=3)]})
    d = dispatcher(model, robot)
    execute = behaviour(d, "(!pick cup)", "execute")
    monitor = behaviour(d, "(!pick cup)", "monitor")
    d.root.tick_once()  # initialise starts the skill, update steps it once
    assert robot.trace == [
        ("start", "pick", "cup"),
        ("step", "pick", 1),
        ("check", "arm_clear", True),
    ]
    assert (execute.status, monitor.status, d.root.status) == (
        Status.RUNNING,
        Status.INVALID,
        Status.RUNNING,
    )
    assert of_action(d, "(!pick cup)") == [("start", 1)]
    d.root.tick_once()
    assert robot.trace[-2:] == [("step", "pick", 2), ("check", "arm_clear", True)]
    d.root.tick_once()  # the last step
    d.root.tick_once()  # the skill returns: finished, then the monitor
    monitored = robot.trace.index(("check", "holding", "cup", True))
    assert robot.trace[: monitored + 1] == [
        ("start", "pick", "cup"),
        ("step", "pick", 1),
        ("check", "arm_clear", True),
        ("step", "pick", 2),
        ("check", "arm_clear", True),
        ("step", "pick", 3),
        ("check", "arm_clear", True),
        ("check", "arm_clear", True),  # tick 4: the skill returns, the hold is looked at
        ("check", "holding", "cup", True),
    ]  # and the monitor runs
    assert (execute.status, monitor.status) == (Status.SUCCESS, Status.SUCCESS)
    assert of_action(d, "(!pick cup)") == [
        ("start", 1),
        ("feedback", 1),
        ("finished", 1),
        ("verified", 1),
    ]
    verified = next(e for e in d.log.events if e["event"] == "verified")
    assert verified["sim_t"] == pytest.approx(3 * DT)
    # the same tick goes on to the next step: place starts and steps once
    assert robot.trace[monitored + 1 :] == [("start", "place", "cup"), ("step", "place", 1)]
    assert robot.calls["place"] == 1 and of_action(d, "(!place cup)") == [("start", 1)]


def test_a_plan_whose_monitors_all_verify_ends_verified(model):
    robot = ScriptedRobot()
    d = dispatcher(model, robot)
    summary = d.run()
    assert (summary.result, summary.verified, summary.steps, summary.retries) == (
        "verified",
        6,
        6,
        0,
    )
    assert [a for _, a, e, _ in events(d, "verified")] == PLAN
    assert ("hold",) not in robot.trace
    assert d.log.events[-1]["event"] == "summary"
    # the internal operator reaches the belief state only
    assert d.belief.state.has("tallied", ("cup",)) and d.belief.state.has("on", ("book", "shelf"))
    assert summary.sim_time == pytest.approx(4 * 2 * DT)


def test_a_skill_that_fails_ends_the_run_failed_without_a_retry(model):
    robot = ScriptedRobot(skills={"place": [Run(steps=2, ok=False, detail="shelf unreachable")]})
    d = dispatcher(model, robot, retries={"!place": 3})
    summary = d.run()
    assert of_action(d, "(!place cup)") == [("start", 1), ("failed", 1)]
    failed = next(e for e in d.log.events if e["event"] == "failed")
    assert failed["detail"] == "shelf unreachable"
    assert (summary.result, summary.failed_step, summary.failed_at, summary.verified) == (
        "failed",
        "(!place cup)",
        2,
        1,
    )
    assert robot.calls["on_shelf"] == 0  # a failed action is not monitored
    assert robot.trace[-1] == ("hold",) and robot.calls["pick"] == 1  # nothing after it


def test_a_monitor_that_does_not_verify_aborts_and_retries_up_to_the_limit(model):
    robot = ScriptedRobot(checks={"holding": [False, False, True]})
    d = dispatcher(model, robot, retries={"!pick": 2})
    summary = d.run()
    assert of_action(d, "(!pick cup)") == [
        ("start", 1),
        ("feedback", 1),
        ("finished", 1),
        ("aborted", 1),
        ("retrying", 1),
        ("start", 2),
        ("feedback", 2),
        ("finished", 2),
        ("aborted", 2),
        ("retrying", 2),
        ("start", 3),
        ("feedback", 3),
        ("finished", 3),
        ("verified", 3),
    ]
    retrying = [e["detail"] for e in d.log.events if e["event"] == "retrying"]
    assert retrying == ["retry 1 of 2", "retry 2 of 2"]
    assert robot.trace.count(("start", "pick", "cup")) == 3 and summary.retries == 2
    assert summary.result == "verified"


def test_retries_stop_at_the_limit(model):
    robot = ScriptedRobot(checks={"holding": [False]})
    d = dispatcher(model, robot, retries={"!pick": 2})
    summary = d.run()
    assert [e for e, _ in of_action(d, "(!pick cup)")].count("start") == 3
    assert of_action(d, "(!pick cup)")[-1] == ("aborted", 3)
    assert (summary.result, summary.retries, summary.verified, summary.executed) == (
        "aborted",
        2,
        0,
        1,
    )
    assert robot.calls["place"] == 0 and robot.trace[-1] == ("hold",)


def test_no_retries_without_a_limit(model):
    robot = ScriptedRobot(checks={"on_shelf": [False, True]})
    summary = dispatcher(model, robot).run()
    assert (summary.result, summary.retries, summary.failed_step) == ("aborted", 0, "(!place cup)")


def test_a_hold_monitor_that_breaks_mid_action_preempts_the_skill(model):
    # the arm is clear for the first two ticks of the pick, then it is not
    robot = ScriptedRobot(
        skills={"pick": [Run(steps=10)]}, checks={"arm_clear": [True, True, False]}
    )
    d = dispatcher(model, robot, retries={"!pick": 2})
    summary = d.run()
    assert robot.trace == [
        ("start", "pick", "cup"),
        ("step", "pick", 1),
        ("check", "arm_clear", True),
        ("step", "pick", 2),
        ("check", "arm_clear", True),
        ("step", "pick", 3),
        ("check", "arm_clear", False),
        ("preempted", "pick", 3),
        ("hold",),  # the skill closed where it was, held
        ("hold",),
    ]  # the run ends: the robot holds its pose
    assert of_action(d, "(!pick cup)") == [("start", 1), ("aborted", 1)]
    aborted = next(e for e in d.log.events if e["event"] == "aborted")
    assert aborted["hold"] == "the arm is clear"
    assert aborted["detail"].startswith("the arm is clear no longer holds: arm_clear")
    assert aborted["sim_t"] == pytest.approx(3 * DT)  # at that tick's simulated time
    # preempted: not monitored, and not retried (retrying cannot restore what broke)
    assert robot.calls["holding"] == 0
    assert (summary.result, summary.retries, summary.sim_time) == ("aborted", 0, 0.3)


def test_an_instantaneous_skill_finishes_in_its_first_tick(model):
    robot = ScriptedRobot(skills={"pick": [Run(steps=0)]})
    d = dispatcher(model, robot)
    d.root.tick_once()
    assert of_action(d, "(!pick cup)") == [
        ("start", 1),
        ("feedback", 1),
        ("finished", 1),
        ("verified", 1),
    ]
    # the parallel ticks its hold-monitor once beside it, then the monitor runs
    assert robot.trace[:3] == [
        ("start", "pick", "cup"),
        ("check", "arm_clear", True),
        ("check", "holding", "cup", True),
    ]


# ------------------------------------------------------------------ halt


def test_halt_between_ticks_preempts_the_running_skill(model):
    robot = ScriptedRobot(skills={"place": [Run(steps=50)]})
    d = dispatcher(model, robot)
    while robot.calls["place"] == 0 or robot.trace[-1] != ("step", "place", 2):
        d.root.tick_once()
    stepped = robot.steps
    d.halt("stopped by the test")
    summary = d.run()
    assert robot.steps == stepped  # no tick after the halt
    assert robot.trace[-3:] == [("preempted", "place", 2), ("hold",), ("hold",)]
    assert (summary.result, summary.verified, summary.failed_step) == (
        "interrupted",
        1,
        "(!place cup)",
    )
    last = d.log.events[-2]
    assert (last["event"], last["action"], last["detail"]) == (
        "interrupted",
        "(!place cup)",
        "stopped by the test; the robot holds its pose",
    )
    assert all(b.status == Status.INVALID for b in d.root.iterate())


def test_a_halt_during_a_tick_takes_effect_before_the_next(model):
    # as Ctrl-C in htn run: the signal handler halts the dispatcher mid-tick
    robot = ScriptedRobot(skills={"pick": [Run(steps=50)]})
    d = dispatcher(model, robot)
    robot.on_step = lambda r: r.steps == 4 and d.halt()
    summary = d.run()
    assert robot.steps == 4 and summary.result == "interrupted"
    assert d.log.events[-2]["detail"] == "stopped by the user; the robot holds its pose"


def test_a_halt_while_the_outcome_is_being_recorded_does_not_deadlock(model):
    """A signal handler's halt() runs in the main thread, whatever it holds:
    here while report() applies the verified step to the belief, under the
    dispatcher's lock (the deadline of htn run arriving there hung the long
    fuzz run). The run ends interrupted instead of waiting for itself."""
    import threading

    robot = ScriptedRobot()
    d = dispatcher(model, robot)
    apply_step = d.belief.apply_step

    def interrupted_apply(*args):
        d.halt()  # as the signal handler would, mid-update
        return apply_step(*args)

    d.belief.apply_step = interrupted_apply  # type: ignore[method-assign]
    out: list = []
    t = threading.Thread(target=lambda: out.append(d.run()), daemon=True)
    t.start()
    t.join(30)
    assert out and out[0].result == "interrupted", "the run waited for its own lock"


def test_a_halt_before_the_first_tick_starts_nothing(model):
    robot = ScriptedRobot()
    d = dispatcher(model, robot)
    d.halt()
    summary = d.run()
    assert robot.trace == [("hold",)] and summary.executed == 0
    assert d.log.events[-2]["detail"] == "stopped by the user before the first step"


def test_a_halt_for_another_goal_ends_the_run_preempted_and_says_why(model):
    robot = ScriptedRobot(skills={"pick": [Run(steps=50)]})
    d = dispatcher(model, robot)
    robot.on_step = lambda r: r.steps == 2 and d.halt("a newer goal", "preempted")
    summary = d.run()
    assert (summary.result, summary.reason, summary.failed_step) == (
        "preempted",
        "a newer goal",
        "(!pick cup)",
    )
    assert summary.line().startswith("preempted: 0 of 6 steps verified")
    halted, last = d.log.events[-2:]
    assert halted["detail"] == "a newer goal; the robot holds its pose"
    assert (last["event"], last["result"], last["reason"]) == (
        "summary",
        "preempted",
        "a newer goal",
    )


def test_a_halt_after_the_running_action_lets_it_end_and_stops_before_the_next(model):
    robot = ScriptedRobot(skills={"pick": [Run(steps=5)], "place": [Run(steps=5)]})
    d = dispatcher(model, robot)
    seen = []

    def newer_goal(r):
        if r.steps == 2:
            ctx, facts = d.running_action()
            seen.append((ctx.text, sorted(facts)))
            d.halt("a newer goal", "preempted", after=ctx)
            assert d.running_action() is None  # halted: nothing more goes on from it

    robot.on_step = newer_goal
    summary = d.run()
    assert seen == [("(!pick cup)", [("on", ("book", "table")), ("on", ("cup", "table"))])]
    assert robot.calls["place"] == 0 and robot.steps == 5  # the pick went on to its end
    assert (summary.result, summary.verified, summary.failed_step) == ("preempted", 1, None)
    assert d.log.events[-2]["step"] is None  # halted between two actions


def test_a_halt_after_an_action_that_has_ended_halts_at_once(model):
    robot = ScriptedRobot(skills={"pick": [Run(steps=1)], "place": [Run(steps=50)]})
    d = dispatcher(model, robot)
    pick = actions(d.root)[0]
    robot.on_step = lambda r: r.calls["place"] and d.halt("a newer goal", "preempted", after=pick)
    summary = d.run()
    assert robot.trace[-3] == ("preempted", "place", 1)
    assert (summary.result, summary.failed_step) == ("preempted", "(!place cup)")


def test_adopted_steps_are_logged_verified_and_not_run_again(model):
    robot = ScriptedRobot()
    d = dispatcher(model, robot)
    d.adopt(1, "verified in the run before")
    summary = d.run()
    assert robot.calls["pick"] == 1  # the book's; the cup's was adopted
    assert of_action(d, "(!pick cup)") == [("verified", 1)]
    adopted = next(e for e in d.log.events if e["action"] == "(!pick cup)")
    assert adopted["adopted"] and adopted["step"] == 1
    assert (summary.result, summary.verified, summary.executed) == ("verified", 6, 6)


# ------------------------------------------------------------------ repair


def test_repair_grafts_a_new_plan_for_the_enclosing_task_from_the_observed_world(model):
    # the cup is not picked (the monitor never sees it held): the robot sees
    # it on the floor, so the cup's shelve task is planned again from there
    world = [("on", ("cup", "floor")), ("on", ("book", "table"))]
    robot = ScriptedRobot(checks={"holding": [False, True]}, world=world)
    d = dispatcher(model, robot, replan=True)
    old_task = d.root.children[0].children[0]
    summary = d.run()
    replanned = next(e for e in d.log.events if e["event"] == "replanned")
    assert replanned["steps"] == ["(!lift cup)", "(!place cup)", "(!!tally cup)"]
    assert replanned["tasks"] == ["(shelve cup)"]
    assert old_task.name == "tidy/shelve :call 1"
    assert replanned["path"] == old_task.name and replanned["tried"] == [old_task.name]
    assert replanned["plan"] == [
        "(!lift cup)",
        "(!place cup)",
        "(!!tally cup)",
        "(!pick book)",
        "(!place book)",
        "(!!tally book)",
    ]
    # the new subtree sits where the old one was, under the same node path
    tidy = d.root.children[0]
    new_task = tidy.children[0]
    assert new_task is not old_task and new_task.name == old_task.name
    assert [a.text for a in actions(new_task)] == replanned["steps"]
    assert [a.text for a in actions(d.root)] == replanned["plan"]
    # and the tree goes on from there, to the end
    assert robot.calls["lift"] == 1 and robot.calls["pick"] == 2
    assert [a for _, a, e, _ in events(d, "verified")] == replanned["plan"]
    assert (summary.result, summary.replans, summary.verified, summary.steps) == (
        "verified",
        1,
        6,
        6,
    )


def test_no_repair_when_the_observed_world_has_no_plan(model):
    # the robot sees the cup nowhere: no enclosing task can be planned
    robot = ScriptedRobot(checks={"holding": [False]}, world=[("on", ("book", "table"))])
    d = dispatcher(model, robot, replan=True)
    summary = d.run()
    failed = next(e for e in d.log.events if e["event"] == "replan_failed")
    assert len(failed["tried"]) >= 2 and failed["tried"][-1] == "plan"
    assert (summary.result, summary.replans) == ("aborted", 0)
    assert robot.trace[-1] == ("hold",)
