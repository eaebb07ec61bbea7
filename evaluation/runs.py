"""The runs of an evaluation: plans executed on a robot, each run measured
(the metrics of :mod:`htn.transform.projection`).

A :class:`Study` holds everything a run needs and is small enough to send to a
Dask worker: domain, problem instance, the plans to compare, retry limits,
the robot's name and its ``--faults``. A process prepares a study once
(:func:`run_batch` keeps it, keyed by its content) and then executes runs of
it; run ``i`` of an evaluation uses seed ``seed + i`` for every plan, so a run
is the same wherever and in whatever order it executes.

The robots that can be evaluated are in :data:`MEASURES`, each with how its
robot is built for a run and how its metrics are read.
"""

from __future__ import annotations

import hashlib
import pickle
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

from htn.executor.dispatcher import RunSummary
from htn.jshop.language import syntax as S
from htn.robot.faults import Faults
from htn.robot.projection import FailureRates, ProjectionRobot, world_from_atoms
from htn.transform.projection import measured_run, projection_metrics


@dataclass
class Study:
    """A plan comparison as a worker receives it; ``plans`` maps a name
    ("original", "transformed") to its steps."""

    domain: S.Domain
    instance: S.ProblemInstance
    plans: dict
    retries: dict = field(default_factory=dict)
    robot: str = "projection"
    faults: str = ""

    def pack(self) -> tuple[str, bytes]:
        """The study pickled, and a key naming its content."""
        blob = pickle.dumps(self, protocol=pickle.HIGHEST_PROTOCOL)
        return hashlib.sha256(blob).hexdigest()[:16], blob


# ------------------------------------------------------------------ robots


@dataclass
class Measure:
    """How one robot back end is evaluated: the fault kinds it injects, how
    a process prepares a study for it (once), how it builds the robot of a
    run, how it reads the run's distances and failed attempts, and how many
    runs make a batch (about 40 ms of projection, one physics run: enough
    to outweigh sending a task, few enough to balance the workers)."""

    fault_kinds: tuple
    prepare: Callable  # Study -> what robot() needs, built once per process
    robot: Callable  # (prepared, seed) -> robot
    read: Callable  # (robot, RunSummary) -> {navigation, manipulation, actions, failed}
    description: str
    batch: int
    # each plan's run a task of its own: a physics run takes seconds, and at
    # the end of a study the workers wait for the last task
    per_plan: bool = False
    # seconds a run of one plan takes at the least, on any machine (0: not
    # known): with it, a study large enough starts its workers before its
    # runs are measured (:func:`.placement.start_early`)
    least: float = 0.0


def _projection_prepare(study: Study):
    # the paper's projection fails now and then: its rates are the default,
    # and --faults overrides some of them
    return world_from_atoms(study.instance.state), FailureRates().with_faults(study.faults)


def _pybullet_robot(study: Study, seed: int):
    # a fresh physics world per run: a run is then a function of its seed alone
    from htn.robot.backends import RobotRequest, make_robot

    return make_robot("pybullet", RobotRequest(study.domain, study.instance, study.faults, seed))


def _pybullet_read(robot, summary: RunSummary) -> dict:
    # the physics robot has no failure draws: a failed attempt is one its
    # monitor did not verify (aborted or failed)
    attempts = summary.executed + summary.retries  # steps started, then their retries
    return {
        "navigation": robot.odometry.base,
        "manipulation": robot.odometry.grippers,
        "actions": attempts,
        "failed": attempts - summary.verified,
    }


MEASURES: dict[str, Measure] = {
    "projection": Measure(
        FailureRates.kinds(),
        _projection_prepare,
        lambda prepared, seed: ProjectionRobot(prepared[0], seed=seed, failures=prepared[1]),
        projection_metrics,
        "projected",
        batch=25,
    ),
    "pybullet": Measure(
        Faults.kinds(),
        lambda study: study,
        _pybullet_robot,
        _pybullet_read,
        "PyBullet",
        batch=1,
        per_plan=True,
        least=0.5,
    ),  # 2.1-2.4 s on this 2-core machine
}


def execute(study: Study, prepared, name: str, seed: int, outcomes: bool = False) -> dict:
    """One run of the plan ``name``: its metrics, sim time and result; with
    ``outcomes``, also each step's final outcome (0-based step -> event)."""
    measure = MEASURES[study.robot]
    robot = measure.robot(prepared, seed)
    return measured_run(
        robot,
        measure.read,
        study.domain,
        study.instance,
        study.plans[name],
        study.retries,
        outcomes,
    )


_PREPARED: OrderedDict = OrderedDict()  # study key -> (study, prepared), this process's
_KEEP = 4


def run_batch(key: str, blob: bytes, runs: list, plans: tuple | None = None) -> list[dict]:
    """Execute runs ``[(number, seed), ...]`` of a packed study, each of
    ``plans`` (default: every plan) once per run; one record per plan
    execution. The study is unpacked and prepared once per process and kept
    for the next batches."""
    if key not in _PREPARED:
        study = pickle.loads(blob)
        _PREPARED[key] = (study, MEASURES[study.robot].prepare(study))
        while len(_PREPARED) > _KEEP:
            _PREPARED.popitem(last=False)
    study, prepared = _PREPARED[key]
    _PREPARED.move_to_end(key)
    return [
        {"run": number, "seed": seed, "plan": name, **execute(study, prepared, name, seed)}
        for number, seed in runs
        for name in (plans or study.plans)
    ]
