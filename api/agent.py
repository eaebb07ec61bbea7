"""A planner and executor that lives across goals: the use case under a
robot node (issue 36), with no middleware in it.

An :class:`Agent` holds a :class:`~htn.api.world.WorldModel` and one robot
for its whole life. Each goal (a task list) is planned from what the world
model believes now, run with the same executor, monitors, retries and
repair as ``htn run``, and what the run verified becomes the world model.
A goal ends in one of five outcomes:

* ``verified``, ``failed``, ``aborted``: as ``htn run``;
* ``preempted``: :meth:`Agent.preempt` halted it (a cancel, or a newer
  goal): the running action's skill is stopped and the robot holds its
  pose; the steps verified so far stay in the world model;
* ``refused``: the goal could not be planned (a located error in its text,
  or no plan from the current state); nothing moved.

One goal runs at a time; :meth:`execute` is meant to be called from one
thread, :meth:`preempt` and :meth:`plan` from any.
"""
from __future__ import annotations

import json
import threading
from dataclasses import dataclass, field
from typing import Callable, Optional

from htn.jshop.language.errors import HtnError

from .world import WorldModel, plan_goal

PREEMPTED = "preempted by a newer goal or a cancel"


@dataclass
class GoalResult:
    """How a goal ended (the fields of ``ExecuteTasks``' result)."""
    outcome: str                 # verified | failed | aborted | preempted | refused
    summary: str = ""            # the line htn run prints
    error: str = ""              # the located error, when refused
    plan: list = field(default_factory=list)     # the steps, as executed
    tree: str = ""               # the plan's task tree, JSON
    steps: int = 0
    verified: int = 0
    log: list = field(default_factory=list)      # every event, as logged

    @property
    def ok(self) -> bool:
        return self.outcome == "verified"


class Agent:
    """Plans and runs goals on one robot, keeping a world model between them.

    ``domain``, ``problem`` (the first state; optional), ``functions``: as
    :class:`~htn.api.world.WorldModel`. ``robot``: a back end's name (built
    once, for the problem's world) or a :class:`~htn.robot.interface.Robot`.
    ``faults``, ``seed``, ``retries``, ``replan``: as :func:`htn.api.run.run`,
    for every goal. ``stops``: the process's :class:`htn.process.Stops`."""

    def __init__(self, domain, problem=None, *, robot="symbolic", functions=None,
                 faults: str = "", seed: int = 0, retries=None, replan: bool = False,
                 stops=None):
        self.world = WorldModel(domain, problem, functions, stops)
        self.retries, self.replan, self.stops = retries, replan, stops
        self.robot_name = robot if isinstance(robot, str) else type(robot).__name__
        self.robot = self._robot(robot, faults, seed) if isinstance(robot, str) else robot
        self._running = None             # the Execution of the goal being run
        self._preempted: Optional[str] = None
        self._lock = threading.Lock()
        _warm_up()

    def _robot(self, name: str, faults: str, seed: int):
        from htn.robot.backends import RobotRequest, make_robot

        from .extras import require_robot_extra
        require_robot_extra(name, f"the {name} robot")
        problem = self.world.problem("()", "world")      # the world as believed, no tasks
        return make_robot(name, RobotRequest(self.world.domain, problem.instances[0], faults,
                                             seed, False, self.world.functions))

    # ------------------------------------------------------------ goals
    def plan(self, tasks: str, source: str = "goal"):
        """The first plan of ``tasks`` from the current world model, or None
        if there is none (an :class:`HtnError` for a bad goal)."""
        return self._first_plan(tasks, source)[0]

    def _first_plan(self, tasks: str, source: str) -> tuple:
        """(the first plan or None, the goal's problem it was planned in):
        the goal read once, so the run checks the plan in the very state it
        was made from, whatever facts arrive meanwhile."""
        stream = plan_goal(self.world, tasks, source=source, stops=self.stops)
        try:
            return next(iter(stream), None), stream.problem
        finally:
            stream.close()

    def execute(self, tasks: str, *, source: str = "goal", log=None,
                on_event: Optional[Callable[[dict], None]] = None) -> GoalResult:
        """Plan ``tasks`` from the world model and run the plan on the robot;
        ``on_event`` gets every event as it is logged (and ``log``, a path,
        the JSON Lines log of ``htn run``)."""
        from .run import prepare
        self._observe()
        try:
            plan, problem = self._first_plan(tasks, source)
            if plan is None:
                raise HtnError("no plan reaches the goal from the current state", source)
        except HtnError as exc:
            return GoalResult("refused", f"refused: {exc.message}", error=str(exc))
        execution = prepare(plan, robot=self.robot, domain=self.world.domain, problem=problem,
                            retries=self.retries, replan=self.replan, log=log,
                            on_event=on_event, stops=self.stops)
        with self._lock:
            self._running, self._preempted = execution, None
        try:
            with execution:
                execution.begin()
                try:
                    result = execution.execute()
                except KeyboardInterrupt as exc:    # outside the ticks: the log ends in order
                    result = execution.interrupted(str(exc))
                self.world.believe(execution.believed())
        finally:
            with self._lock:
                self._running = None
        return self._result(plan, result)

    def _observe(self) -> None:
        """A robot that observes the world itself (``observes_world``: a
        robot in another process, which may have been restarted or moved
        meanwhile) is asked what it sees before a goal is planned; its
        observation replaces the believed facts of the dynamic predicates."""
        if getattr(self.robot, "observes_world", False):
            facts = self.robot.observe()
            if facts:
                self.world.observed(facts)

    def preempt(self, why: str = PREEMPTED) -> bool:
        """Halt the goal being run at its current action (the robot holds
        its pose); it ends ``preempted``. False if none runs."""
        with self._lock:
            if self._running is None:
                return False
            self._preempted = why
            self._running.halt(why)
            return True

    def _result(self, plan, result) -> GoalResult:
        s = result.summary
        outcome = s.result
        if outcome == "interrupted" and self._preempted is not None:
            outcome = "preempted"
        line = s.line()
        if outcome == "preempted":
            line = "preempted" + line[len("interrupted"):]
        tree = json.dumps(plan.tree.to_dict()) if plan.tree is not None else ""
        return GoalResult(outcome, line, plan=list(result.plan), tree=tree, steps=s.steps,
                          verified=s.verified, log=list(result.events))


def _warm_up() -> None:
    """Load now what the first goal would load (the executor, py_trees, the
    action machines and their plugins, about 0.1 s), so that a goal's first
    action starts as soon after its plan as every later goal's."""
    from htn.executor.machines.base import load_plugins

    from . import run  # noqa: F401  (the executor and py_trees)
    load_plugins()
