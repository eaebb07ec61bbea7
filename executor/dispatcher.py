"""Task dispatcher and task executor (the paper's task management, section 4).

The **task dispatcher** walks the plan and sends one step at a time to the
**task executor**, which parses the step into a name and parameters and runs
the action state machine registered for that operator (:mod:`htn.executor.actions`),
retrying it while its monitor does not verify it, up to the operator's limit.
Internal operators (``!!``) are not sent to the robot: they are applied to the
belief state only.

When an action ends failed or aborted, the robot stops and holds its pose (as
in the paper). With ``replan=True`` the dispatcher instead builds the current
state from what the robot observes, plans the original tasks again from there
and continues with the new plan.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from htn.jshop import syntax as S
from htn.jshop.planner import Planner

from .actions import Outcome, machine_for
from .log import EventLog


@dataclass
class RunSummary:
    result: str              # verified | failed | aborted | interrupted
    steps: int               # steps executed (all attempts' steps counted once)
    verified: int
    retries: int
    replans: int
    sim_time: float
    failed_step: Optional[str] = None

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def dynamic_predicates(domain: S.Domain) -> set[str]:
    """Predicates some operator adds or deletes: the ones to observe."""
    return domain.dynamic_predicates()


class TaskExecutor:
    """Runs one plan step on the robot through its action state machine."""

    def __init__(self, robot, retries: dict[str, int], log: EventLog,
                 domain: Optional[str] = None):
        self.robot = robot
        self.retries = retries
        self.log = log
        self.domain = domain
        self.retry_count = 0

    def execute(self, index: int, step) -> Outcome:
        name, args = step.name, tuple(step.args)
        action = str(step)
        machine = machine_for(name, self.domain, self.robot)
        if machine is None:
            self.log.emit(index, action, Outcome.FAILED.value, 1,
                          f"no action state machine is registered for {name}")
            return Outcome.FAILED
        limit = self.retries.get(name, 0)
        attempt = 1
        while True:
            self.log.emit(index, action, "start", attempt, "")

            def emit(event: str, detail: str, attempt=attempt) -> None:
                if event == Outcome.FINISHED.value:
                    self.log.emit(index, action, "feedback", attempt, detail)
                self.log.emit(index, action, event, attempt, detail)

            outcome = machine.run(self.robot, args, emit)
            if outcome is Outcome.ABORTED and attempt <= limit:
                self.log.emit(index, action, Outcome.RETRYING.value, attempt,
                              f"retry {attempt} of {limit}")
                self.retry_count += 1
                attempt += 1
                continue
            return outcome


class TaskDispatcher:
    """Walks a plan, dispatching each step to the task executor."""

    def __init__(self, robot, domain: S.Domain, instance: S.ProblemInstance, steps: list,
                 retries: dict[str, int], log: EventLog, replan: bool = False,
                 functions=None, max_replans: int = 3):
        self.robot = robot
        self.domain = domain
        self.instance = instance
        self.steps = list(steps)
        self.log = log
        self.replan = replan
        self.functions = functions
        self.max_replans = max_replans
        self.executor = TaskExecutor(robot, retries, log, domain.name)
        self.belief = Planner(domain, S.ProblemInstance(instance.state, S.TaskList([])), functions)

    def run(self) -> RunSummary:
        verified = executed = replans = 0
        steps = self.steps
        i = 0
        try:
            while i < len(steps):
                step = steps[i]
                executed += 1
                if step.internal:
                    ok = self.belief.apply_step(step.name, step.args)
                    if ok:
                        self.robot.apply_internal(step.name, step.args)
                    self.log.emit(i, str(step), Outcome.VERIFIED.value if ok else Outcome.FAILED.value,
                                  1, "internal operator applied to the belief state"
                                  if ok else "internal operator not applicable")
                    if ok:
                        verified += 1
                        i += 1
                        continue
                    outcome = Outcome.FAILED
                else:
                    outcome = self.executor.execute(i, step)
                    if outcome is Outcome.VERIFIED:
                        self.belief.apply_step(step.name, step.args)
                        verified += 1
                        i += 1
                        continue
                if self.replan and replans < self.max_replans:
                    new = self._replan(i, step)
                    if new is not None:
                        replans += 1
                        steps, i = new, 0
                        continue
                self.robot.hold()
                return self._summary(outcome.value, executed, verified, replans, str(step))
        except KeyboardInterrupt:
            self.robot.hold()
            self.log.emit(i if i < len(steps) else None, str(steps[i]) if i < len(steps) else None,
                          "interrupted", None, "stopped by the user; the robot holds its pose")
            return self._summary("interrupted", executed, verified, replans, None)
        return self._summary(Outcome.VERIFIED.value, executed, verified, replans, None)

    def _summary(self, result, executed, verified, replans, failed) -> RunSummary:
        summary = RunSummary(result, executed, verified, self.executor.retry_count, replans,
                             round(self.robot.sim_time, 3), failed)
        self.log.emit(None, None, "summary", None, result, **summary.as_dict())
        return summary

    def observed_instance(self) -> S.ProblemInstance:
        """The current state as the robot observes it: static facts of the
        problem plus the observed facts of the domain's dynamic predicates."""
        dynamic = dynamic_predicates(self.domain)
        atoms = [a for a in self.instance.state if a.pred not in dynamic]
        for pred, args in self.robot.observe():
            atoms.append(S.Atom(pred, tuple(args)))
        return S.ProblemInstance(atoms, self.instance.tasks, self.instance.pos)

    def _replan(self, index: int, step) -> Optional[list]:
        instance = self.observed_instance()
        planner = Planner(self.domain, instance, self.functions)
        plan = next(planner.plans(timeout=30.0), None)
        if plan is None:
            self.log.emit(index, str(step), "replanned", None,
                          "no plan from the observed state")
            return None
        self.instance = instance
        self.belief = Planner(self.domain, S.ProblemInstance(instance.state, S.TaskList([])),
                              self.functions)
        self.log.emit(index, str(step), "replanned", None,
                      f"new plan of {len(plan.steps)} steps from the observed state",
                      plan=plan.lines())
        return plan.steps
