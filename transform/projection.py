"""One run of a plan on a robot, and the metrics measured in it (the
plan-transformations paper, Section IV-A): **navigation** and
**manipulation**, the distances travelled by the robot's base and grippers;
**actions**, the action attempts (steps and retries); **failures**, the share
of attempts that failed.

The framework's projected costs (:func:`htn.transform.framework.projected`)
run plans on the fast projection robot with :func:`project`; the evaluation
(:mod:`htn.evaluation`) runs many of them, on any robot it can measure.
"""

from __future__ import annotations

from collections.abc import Callable

from htn.executor.dispatcher import RunSummary, TaskDispatcher
from htn.executor.log import EventLog
from htn.jshop.language import syntax as S
from htn.robot.projection import FailureRates, ProjectionRobot, world_from_atoms


def run_plan(
    robot, domain: S.Domain, instance: S.ProblemInstance, steps, retries: dict
) -> tuple[RunSummary, EventLog]:
    """Dispatch ``steps`` on ``robot`` once, with per-action monitoring."""
    log = EventLog(None, clock=lambda: robot.sim_time)
    return TaskDispatcher(robot, domain, instance, steps, retries, log).run(), log


def measured_run(
    robot,
    read: Callable,
    domain: S.Domain,
    instance: S.ProblemInstance,
    steps,
    retries: dict,
    outcomes: bool = False,
) -> dict:
    """Run ``steps`` once on ``robot`` (closed afterwards): the metrics ``read``
    takes from it, sim time and result; with ``outcomes``, also each step's
    final outcome (0-based step -> event)."""
    try:
        summary, log = run_plan(robot, domain, instance, steps, retries)
        record = read(robot, summary)
        if outcomes:
            record["outcomes"] = {
                e["step"] - 1: e["event"]
                for e in log.events  # 1-based steps
                if e["event"] in ("verified", "aborted", "failed") and e["step"] is not None
            }
    finally:
        close = getattr(robot, "close", None)
        if close:
            close()
    record["failures"] = record["failed"] / max(record["actions"], 1)
    record["sim_time"] = robot.sim_time
    record["result"] = summary.result
    return record


def projection_metrics(robot: ProjectionRobot, summary: RunSummary) -> dict:
    m = robot.metrics
    return {
        "navigation": m.navigation,
        "manipulation": m.manipulation,
        "actions": m.actions,
        "failed": m.failures,
    }


def project(
    domain: S.Domain,
    instance: S.ProblemInstance,
    steps,
    seed: int,
    rates: FailureRates | None = None,
    retries: dict | None = None,
) -> dict:
    """Execute ``steps`` once on the projection robot; metrics of the run and
    the outcome of each step (for :func:`projected_tree`).

    ``failures`` is the share of action attempts that failed (0..1); the
    rates default to the paper's (:class:`FailureRates`)."""
    robot = ProjectionRobot(
        world_from_atoms(instance.state), seed=seed, failures=rates or FailureRates()
    )
    return measured_run(
        robot, projection_metrics, domain, instance, steps, retries or {}, outcomes=True
    )


def projected_tree(
    domain: S.Domain,
    instance: S.ProblemInstance,
    plan,
    seed: int = 0,
    retries: dict | None = None,
):
    """The plan's task tree annotated with the outcomes of one projected run."""
    from htn.jshop.plans.tree import annotate

    run = project(domain, instance, plan.steps, seed, retries=retries)
    return annotate(plan.tree, run["outcomes"]), run
