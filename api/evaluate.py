"""The evaluate use case: execute a problem's plan and its transformed plan
many times each and compare them (``htn evaluate``; the plan-transformations
paper, Section IV-A: :mod:`htn.evaluation`).

Run ``i`` uses seed ``seed + i`` for both plans, on the fast projection or
the PyBullet robot, in this process, on a local Dask cluster of ``workers``
processes or on an existing cluster (``scheduler``); the metrics for a seed
are the same on any number of workers. Needs the ``eval`` extra.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Callable, Optional

from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable
from htn.jshop.readers.load import load_problem

from .extras import require_extra, require_robot_extra
from htn.files import check_output_file, check_output_folder, make_output_folder
from .inputs import domain_for, read_inputs


@dataclass
class Evaluation:
    """What an evaluation found: the runs and their comparison
    (``comparison``: a :class:`htn.evaluation.statistics.Comparison`), its
    ``metrics``, the figures written (``plots``), and the cluster's one-line
    ``notes``."""
    problem: str
    comparison: object
    metrics: dict
    plots: list = field(default_factory=list)
    notes: list = field(default_factory=list)

    def document(self) -> dict:
        """The ``htn evaluate --json`` object."""
        c = self.comparison
        return {"problem": self.problem, "runs": c.runs, "applied": c.applied,
                "metrics": self.metrics, "plots": self.plots, "robot": c.robot,
                "results": c.results(), "workers": c.workers,
                "runs_per_s": round(c.runs_per_s, 3)}


def check_evaluation(problem, domain, robot, faults, workers, scheduler, plot, records) -> None:
    """Every input and output of an evaluation, before any work starts (the
    scheduler's address is checked where it is used, by ``open_runner``;
    nothing is written before that)."""
    require_extra("eval", "htn evaluate")
    if not os.path.isfile(problem):
        raise HtnError("no such file", problem)
    if domain is not None and not os.path.isfile(domain):
        raise HtnError("no such file", domain)
    from htn.evaluation.runs import MEASURES
    if robot not in MEASURES:
        raise HtnError(f"--robot {robot}: this robot cannot be evaluated (choose from "
                       f"{', '.join(MEASURES)})")
    require_robot_extra(robot, f"htn evaluate --robot {robot}")
    if scheduler is not None and workers is not None:
        raise HtnError("--workers starts a local cluster, --scheduler uses an existing "
                       "one and its workers: give one of them")
    from htn.robot.faults import parse_faults
    parse_faults(faults, MEASURES[robot].fault_kinds)
    inputs = (problem, domain)
    if plot is not None:
        check_output_folder(plot, "--plot", inputs, [(records, "--records")] if records else ())
    if records is not None:
        check_output_file(records, "--records", inputs, [(plot, "--plot")] if plot else ())


def check_study(study, log: list, problem: str) -> None:
    """A study gives a comparison only if a transformation applied to the
    plan (``log``: the framework's entries; none when no rule's
    applicability rule found a task) and the robot can execute every step of
    both plans (an action state machine for each): else an input error at
    the problem that says why, and what an evaluation needs."""
    from htn.executor.machines.base import machine_for
    from htn.transform.registered import default_framework
    why = []
    if not log:
        rules = ", ".join(t.name for t in default_framework().transformations if t.enabled)
        why.append(f"no registered transformation ({rules}) applies to its plan (the built-in "
                   "ones rewrite top-level (transporting ...) tasks, as in the kitchen domain; "
                   "add rules for another domain: entry points 'htn.transformations')")
    missing: dict = {}
    for steps in study.plans.values():
        for s in steps:
            if not s.internal and machine_for(s.name, study.domain.name) is None:
                missing.setdefault(s.name)
    if missing:
        why.append(f"the {study.robot} robot has no action for {', '.join(missing)} (it runs "
                   "the bundled domestic and kitchen domains' actions and those of plugins: "
                   "entry points 'htn.actions'), so its runs would measure nothing")
    if why:
        raise HtnError("htn evaluate compares a plan with its transformed plan, but "
                       + "; and ".join(why), problem)


def evaluate(problem, *, domain=None, runs: int = 200, seed: int = 0,
             robot: str = "projection", faults: str = "", workers: Optional[int] = None,
             scheduler: Optional[str] = None, records=None, plot=None,
             on_start: Optional[Callable[[int, list], None]] = None,
             on_batch: Optional[Callable[[list, float], None]] = None,
             say: Optional[Callable[[str], None]] = None,
             on_warning: Optional[Callable[[str], None]] = None,
             on_phase: Optional[Callable[[str], None]] = None) -> Evaluation:
    """Plan ``problem`` (a path), transform the plan with every registered
    rule, execute both ``runs`` times and compare navigation, manipulation,
    actions and failures (Welch's t-test; pooled failure proportions with a
    Wilson 95% interval).

    ``domain``: its domain file (default: ``NAME.jshop`` beside the
    problem, in ``../domains/`` beside it, in ``domains/`` here, or the
    bundled one: :func:`htn.api.inputs.domain_for`). ``robot``:
    ``projection`` or ``pybullet``; ``faults``: failure probabilities
    (``"grasp=0.1"``). ``workers``: processes of a local Dask cluster (None
    or 1: this process); ``scheduler``: the address of an existing cluster.
    ``records``: a file for one JSON line per run of each plan (streamed,
    then put in run order); ``plot``: a folder for the figures.
    ``on_start(workers, notes)`` is called once the runner is ready, before
    planning; ``on_batch(records, runs)`` with each batch's new records and
    the number of runs of every plan they complete; ``say`` gets the line
    that says why a study too small for local workers stays in this process
    (:func:`htn.evaluation.placement.place`); ``on_warning`` each located
    warning (the inputs' check, and rewrites all rolled back); ``on_phase``
    a few words as each phase before the runs begins.

    A study that cannot give a comparison is an input error, raised before
    any run: no registered transformation applies to the plan (the two
    plans would be the same), or the robot has no action state machine for
    some of its steps (every run would fail at once, measuring nothing). A
    cluster that cannot complete the runs raises
    :class:`htn.evaluation.cluster.ClusterError`.
    """
    problem = os.fspath(problem)
    domain = None if domain is None else os.fspath(domain)
    records = None if records is None else os.fspath(records)
    plot = None if plot is None else os.fspath(plot)
    check_evaluation(problem, domain, robot, faults, workers, scheduler, plot, records)
    phase = on_phase or (lambda text: None)
    phase("reading the problem and its domain")
    # each file is read once: the problem names its domain when none is given
    prob = load_problem(problem)
    inputs = read_inputs(domain or domain_for(prob), prob, FunctionTable())
    dom = inputs.domain
    for w in inputs.warnings if on_warning else ():
        on_warning(w)

    from htn.evaluation.cluster import open_runner
    from htn.evaluation.study import (RecordsFile, plot as figures, prepare_study, run_study,
                                      start_workers_early)

    stream = None
    try:
        with open_runner(workers or 1, scheduler) as runner:
            if plot is not None:    # all options are checked now (the scheduler last)
                make_output_folder(plot, "--plot")
            notes = list(runner.notes)
            if on_start:
                on_start(runner.workers, notes)
            log: list = []
            start_workers_early(runner, robot, runs)
            study, applied = prepare_study(dom, prob, robot, faults, log=log, on_phase=phase)
            check_study(study, log, problem)
            if log and not applied and on_warning:
                on_warning(f"{problem}: warning: every rewrite was rolled back ("
                           + "; ".join(f"{rule}: {detail}" for rule, _, detail in log)
                           + "): both plans are the same")
            stream = RecordsFile(records) if records else None
            phase(f"{runs} runs of each plan on the {robot} robot")

            def batch(new: list) -> None:
                if stream:
                    stream.write(new)
                if on_batch:
                    on_batch(new, len(new) / len(study.plans))

            comp = run_study(study, problem, applied, runs, seed, runner, batch, say)
    finally:
        if stream:
            stream.close()
    if stream:
        stream.finish(comp)
    metrics = comp.metrics()
    plots = figures(comp, plot) if plot else []
    return Evaluation(problem, comp, metrics, plots, notes)
