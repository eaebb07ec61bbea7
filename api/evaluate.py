"""The evaluate use case: execute a problem's plan and its transformed plan
many times each and compare them (``htn evaluate``; the plan-transformations
paper, Section IV-A: :mod:`htn.evaluation`).

Run ``i`` uses seed ``seed + i`` for both plans, on the fast projection or
the PyBullet robot, in this process, on a local Dask cluster of ``workers``
processes or on an existing cluster (``scheduler``); the metrics for a seed
are the same on any number of workers. Needs the ``eval`` extra.

One entry, :func:`evaluate`: its settings are an :class:`EvaluateOptions`
(or the same names as keywords), and what it tells as it goes goes to one
:class:`Progress` object. The names a front end needs to show the result
are here too (:data:`METRIC_NAMES`, :func:`format_change`, :func:`format_p`,
:class:`ClusterError`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING, Any

from htn.evaluation.cluster import ClusterError
from htn.evaluation.statistics import METRIC_NAMES, applied_rules, format_change, format_p
from htn.files import check_output_file, check_output_folder, make_output_folder
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable
from htn.jshop.readers.load import load_problem

from .extras import require_extra, require_robot_extra
from .inputs import domain_for, read_inputs

if TYPE_CHECKING:
    from htn.evaluation.runs import Study
    from htn.evaluation.statistics import Comparison
    from htn.jshop.language import syntax as S

    from .inputs import StrPath

__all__ = [
    "evaluate",
    "EvaluateOptions",
    "Progress",
    "Evaluation",
    "ClusterError",
    "METRIC_NAMES",
    "format_change",
    "format_p",
]


class Progress:
    """What an evaluation tells as it goes: pass one to :func:`evaluate` and
    override the methods you want; each does nothing here."""

    def started(self, workers: int, notes: list[str]) -> None:
        """The runner is ready (before planning): its ``workers`` and the
        cluster's one-line ``notes`` (e.g. package versions that differ)."""

    def phase(self, text: str) -> None:
        """A few words as each phase before the runs begins (reading,
        planning, each rule, the runs)."""

    def batch(self, records: list[dict[str, Any]], runs: float) -> None:
        """A batch's new ``records`` (one per run of a plan) and the number
        of runs of every plan they complete (a fraction when a batch holds
        some of a run's plans)."""

    def note(self, text: str) -> None:
        """The line that says why a study too small for local workers stays
        in this process (:func:`htn.evaluation.placement.place`)."""

    def warning(self, text: str) -> None:
        """A located warning: the inputs' check, and rewrites all rolled back."""


@dataclass(frozen=True)
class EvaluateOptions:
    """How an evaluation runs (``htn evaluate``'s options). ``runs`` of each
    plan, run ``i`` with seed ``seed + i``; ``robot``: ``projection`` or
    ``pybullet``; ``faults``: failure probabilities (``"grasp=0.1"``);
    ``workers``: processes of a local Dask cluster (None or 1: this
    process); ``scheduler``: the address of an existing cluster;
    ``records``: a file for one JSON line per run of each plan (streamed,
    then put in run order); ``plot``: a folder for the figures."""

    runs: int = 200
    seed: int = 0
    robot: str = "projection"
    faults: str = ""
    workers: int | None = None
    scheduler: str | None = None
    records: str | None = None
    plot: str | None = None

    def __post_init__(self) -> None:
        for name in ("records", "plot"):  # paths as str (a Path is welcome)
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, os.fspath(value))


@dataclass
class Evaluation:
    """What an evaluation found: the runs and their comparison
    (``comparison``: a :class:`htn.evaluation.statistics.Comparison`), its
    ``metrics``, the figures written (``plots``), and the cluster's one-line
    ``notes``."""

    problem: str
    comparison: Comparison
    metrics: dict[str, Any]
    plots: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)

    def document(self) -> dict[str, Any]:
        """The ``htn evaluate --json`` object."""
        c = self.comparison
        return {
            "problem": self.problem,
            "runs": c.runs,
            "applied": c.applied,
            "metrics": self.metrics,
            "plots": self.plots,
            "robot": c.robot,
            "results": c.results(),
            "workers": c.workers,
            "runs_per_s": round(c.runs_per_s, 3),
        }

    def heading(self) -> str:
        """What was run: "20 projected runs of each plan; applied: tray"."""
        from htn.evaluation.runs import MEASURES

        c = self.comparison
        return (
            f"{c.runs} {MEASURES[c.robot].description} run{'s' if c.runs > 1 else ''} "
            f"of each plan; applied: {applied_rules(c.applied)}"
        )


def check_evaluation(problem: str, domain: str | None, options: EvaluateOptions) -> None:
    """Every input and output of an evaluation, before any work starts (the
    scheduler's address is checked where it is used, by ``open_runner``;
    nothing is written before that)."""
    require_extra("eval", "htn evaluate")
    if not os.path.isfile(problem):
        raise HtnError("no such file", problem)
    if domain is not None and not os.path.isfile(domain):
        raise HtnError("no such file", domain)
    from htn.evaluation.runs import MEASURES

    o = options
    if o.robot not in MEASURES:
        raise HtnError(
            f"--robot {o.robot}: this robot cannot be evaluated (choose from {', '.join(MEASURES)})"
        )
    require_robot_extra(o.robot, f"htn evaluate --robot {o.robot}")
    if o.scheduler is not None and o.workers is not None:
        raise HtnError(
            "--workers starts a local cluster, --scheduler uses an existing "
            "one and its workers: give one of them"
        )
    from htn.robot.faults import parse_faults

    parse_faults(o.faults, MEASURES[o.robot].fault_kinds)
    inputs = (problem, domain)
    if o.plot is not None:
        check_output_folder(
            o.plot, "--plot", inputs, [(o.records, "--records")] if o.records else ()
        )
    if o.records is not None:
        check_output_file(o.records, "--records", inputs, [(o.plot, "--plot")] if o.plot else ())


def check_study(study: Study, log: list[tuple[str, str, str]], problem: str) -> None:
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
        why.append(
            f"no registered transformation ({rules}) applies to its plan (the built-in "
            "ones rewrite top-level (transporting ...) tasks, as in the kitchen domain; "
            "add rules for another domain: entry points 'htn.transformations')"
        )
    missing: dict[str, None] = {}
    for steps in study.plans.values():
        for s in steps:
            if not s.internal and machine_for(s.name, study.domain.name) is None:
                missing.setdefault(s.name)
    if missing:
        why.append(
            f"the {study.robot} robot has no action for {', '.join(missing)} (it runs "
            "the bundled domestic and kitchen domains' actions and those of plugins: "
            "entry points 'htn.actions'), so its runs would measure nothing"
        )
    if why:
        raise HtnError(
            "htn evaluate compares a plan with its transformed plan, but " + "; and ".join(why),
            problem,
        )


_OPTIONS = tuple(f.name for f in fields(EvaluateOptions))


def evaluate(
    problem: StrPath,
    options: EvaluateOptions | None = None,
    *,
    domain: StrPath | None = None,
    progress: Progress | None = None,
    **settings: Any,
) -> Evaluation:
    """Plan ``problem`` (a path), transform the plan with every registered
    rule, execute both ``runs`` times and compare navigation, manipulation,
    actions and failures (Welch's t-test; pooled failure proportions with a
    Wilson 95% interval).

    ``domain``: its domain file (default: ``NAME.jshop`` beside the
    problem, in ``../domains/`` beside it, in ``domains/`` here, or the
    bundled one: :func:`htn.api.inputs.domain_for`). ``options``: an
    :class:`EvaluateOptions`; ``settings``: any of its fields by name
    (``runs=20, workers=2``), over ``options``' own. ``progress``: a
    :class:`Progress` told what happens as it happens.

    A study that cannot give a comparison is an input error, raised before
    any run: no registered transformation applies to the plan (the two
    plans would be the same), or the robot has no action state machine for
    some of its steps (every run would fail at once, measuring nothing). A
    cluster that cannot complete the runs raises :class:`ClusterError`.
    """
    unknown = [name for name in settings if name not in _OPTIONS]
    if unknown:
        raise TypeError(
            f"evaluate() got unexpected keyword argument(s) {', '.join(unknown)} "
            f"(its options: {', '.join(_OPTIONS)}; progress: one Progress object)"
        )
    options = replace(options or EvaluateOptions(), **settings)
    progress = progress or Progress()
    problem = os.fspath(problem)
    domain = None if domain is None else os.fspath(domain)
    check_evaluation(problem, domain, options)
    progress.phase("reading the problem and its domain")
    # each file is read once: the problem names its domain when none is given
    prob = load_problem(problem)
    inputs = read_inputs(domain or domain_for(prob), prob, FunctionTable())
    for w in inputs.warnings:
        progress.warning(w)
    comp, notes = _study(problem, inputs.domain, prob, options, progress)
    from htn.evaluation.figures import plot as figures

    plots = figures(comp, options.plot) if options.plot else []
    return Evaluation(problem, comp, comp.metrics(), plots, notes)


def _study(
    problem: str, domain: S.Domain, prob: S.Problem, options: EvaluateOptions, progress: Progress
) -> tuple[Comparison, list[str]]:
    """Open the runner, plan and transform, run both plans: the comparison
    and the cluster's notes. ``--records`` streams the runs as they finish
    and is put in run order once all are in."""
    from htn.evaluation.cluster import open_runner
    from htn.evaluation.study import RecordsFile, prepare_study, run_study, start_workers_early

    o = options
    stream = None
    try:
        with open_runner(o.workers or 1, o.scheduler) as runner:
            if o.plot is not None:  # all options are checked now (the scheduler last)
                make_output_folder(o.plot, "--plot")
            notes = list(runner.notes)
            progress.started(runner.workers, notes)
            log: list[tuple[str, str, str]] = []
            start_workers_early(runner, o.robot, o.runs)
            study, applied = prepare_study(
                domain, prob, o.robot, o.faults, log=log, on_phase=progress.phase
            )
            check_study(study, log, problem)
            if log and not applied:
                progress.warning(
                    f"{problem}: warning: every rewrite was rolled back ("
                    + "; ".join(f"{rule}: {detail}" for rule, _, detail in log)
                    + "): both plans are the same"
                )
            stream = RecordsFile(o.records) if o.records else None
            progress.phase(f"{o.runs} runs of each plan on the {o.robot} robot")

            def batch(new: list[dict[str, Any]]) -> None:
                if stream:
                    stream.write(new)
                progress.batch(new, len(new) / len(study.plans))

            comp = run_study(study, problem, applied, o.runs, o.seed, runner, batch, progress.note)
    finally:
        if stream:
            stream.close()
    if stream:
        stream.finish(comp)
    return comp, notes
