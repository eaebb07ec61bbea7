"""Evaluation of plan transformations (the paper's Section IV-A): a plan and
its transformed version are executed RUNS times each, on the fast projection
or on the PyBullet physics robot, run ``i`` with seed ``seed + i`` for both,
and their metrics are compared (:mod:`.statistics`, :mod:`.figures`).

The runs go to a runner (:mod:`.cluster`): this process, a local Dask cluster
or an existing one. They are sent in batches and come back as batches
finish; results are keyed by run, so a batch redone after a lost worker
counts once, and put in run order. A run depends only on its seed, so the
metrics for a given seed are the same on any number of workers.

The one entry that opens a runner and runs a study is the evaluate use case
(:func:`htn.api.evaluate.evaluate`); these are its steps.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable

from htn.executor.config import load_retries

from .placement import place, start_early
from .runs import MEASURES, Study, run_batch
from .statistics import Comparison

BATCHES_PER_WORKER = 4  # at least, to even out batches of uneven length


def prepare_study(
    domain_path,
    problem_path,
    robot: str = "projection",
    faults: str = "",
    log: list | None = None,
    on_phase: Callable[[str], None] | None = None,
) -> tuple[Study, list]:
    """Plan the problem, transform the plan with every registered rule, and
    return the study of both plans with the names of the rules applied. The
    domain and problem are paths, or a Domain and a Problem already read.
    ``log`` (a list) gets the framework's entries ``(rule, status,
    detail)``; ``on_phase`` a few words as planning and each rule begin."""
    from htn.jshop.language import syntax as S
    from htn.jshop.readers.load import load_inputs
    from htn.transform.framework import Workspace
    from htn.transform.registered import default_framework

    if isinstance(domain_path, S.Domain):
        domain, problem = domain_path, problem_path
        domain_path = domain.file
    else:
        domain, problem = load_inputs(domain_path, problem_path)
    instance = problem.instances[0]
    if on_phase:
        on_phase("planning")
    ws = Workspace.from_problem(domain, instance)
    original = ws.plan
    assert original is not None  # see Workspace.from_problem
    default_framework().apply_all_transformations(ws, on_phase=on_phase)
    if log is not None:
        log.extend(ws.log)
    applied = [rule for rule, status, _ in ws.log if status == "applied"]
    assert ws.plan is not None
    plans = {"original": original.steps, "transformed": ws.plan.steps}
    return Study(
        domain, instance, plans, load_retries(domain_path, domain.operators), robot, faults
    ), applied


def batches(runs: int, seed: int, size: int) -> list[list[tuple[int, int]]]:
    """Runs ``0..runs-1`` as ``(number, seed + number)``, in batches of ``size``."""
    numbered = [(i, seed + i) for i in range(runs)]
    return [numbered[i : i + size] for i in range(0, runs, size)]


def run_study(
    study: Study,
    problem: str,
    applied: list,
    runs: int,
    seed: int,
    runner,
    on_batch: Callable[[list], None] | None = None,
    say: Callable[[str], None] | None = None,
) -> Comparison:
    """Execute ``runs`` runs of every plan of ``study`` on ``runner``;
    ``on_batch`` gets each batch's new records as they arrive. On local
    workers not yet started, batches run here and the rest goes to the
    workers, once they are up, only if that is faster
    (:func:`.placement.place`; ``say`` gets the line that says it is not)."""
    measure = MEASURES[study.robot]
    planned = runner.requested if runner.deferred else runner.workers
    size = max(1, min(measure.batch, math.ceil(runs / (planned * BATCHES_PER_WORKER))))
    key, blob = study.pack()
    tasks: list[tuple]
    if measure.per_plan:
        tasks = [
            (key, blob, batch, (name,))
            for batch in batches(runs, seed, size)
            for name in study.plans
        ]
    else:
        tasks = [(key, blob, batch) for batch in batches(runs, seed, size)]
    share = 1 / len(study.plans) if measure.per_plan else 1  # of a run, a task's plans

    def runs_in(task: tuple) -> float:
        return len(task[2]) * share

    done: dict = {}

    def take(records: list) -> None:
        fresh = [r for r in records if (r["run"], r["plan"]) not in done]
        done.update(((r["run"], r["plan"]), r) for r in fresh)
        if on_batch and fresh:
            on_batch(fresh)

    start = time.perf_counter()
    if runner.deferred:
        runner, results = place(runner, tasks, runs_in, run_batch, take, measure.description, say)
    else:
        results = runner.results(run_batch, tasks)
    workers = runner.workers
    for records in results:
        take(records)
    seconds = time.perf_counter() - start
    comp = Comparison(problem, runs, applied, robot=study.robot, workers=workers, seconds=seconds)
    comp.original = [done[(i, "original")] for i in range(runs)]
    comp.transformed = [done[(i, "transformed")] for i in range(runs)]
    return comp


def start_workers_early(runner, robot: str, runs: int) -> None:
    """Before the study is prepared: start ``runner``'s workers beside the
    planning if ``runs`` runs of the plan and its transformed version on
    ``robot`` are sure to be worth them (:func:`.placement.start_early`)."""
    start_early(runner, runs, 2, MEASURES[robot].least)


class RecordsFile:
    """``--records FILE``: one JSON line per plan execution, appended and
    flushed as batches finish (an interrupted evaluation leaves the runs it
    completed); once all are in, the file is rewritten in run order, in one
    atomic replace, so that it is the same for a seed on any number of workers."""

    def __init__(self, path: str):
        self.path = path
        self.fh = open(path, "w", encoding="utf-8")

    def write(self, records: list) -> None:
        for r in records:
            self.fh.write(json.dumps(r) + "\n")
        self.fh.flush()

    def finish(self, comp: Comparison) -> None:
        from htn.files import atomic_write

        self.fh.close()
        ordered = [r for pair in zip(comp.original, comp.transformed) for r in pair]
        with atomic_write(self.path, "--records") as out:
            out.write("".join(json.dumps(r) + "\n" for r in ordered))

    def close(self) -> None:
        self.fh.close()
