"""Benchmark: the runs of ``htn evaluate`` on 1 and 2 workers.

Times the runs phase of an evaluation (from sending the first batch to the
last result: what the number of workers changes) for projected runs on this
process (1 worker) and on a local Dask cluster of 2 worker processes that is
already up, as a cluster reached with ``--scheduler`` would be. The first
evaluation on fresh workers (they unpack and prepare the study) is shown
apart from the median of the repeats. Then physics runs per minute on the
PyBullet robot, on 1 and 2 workers. Target: 2 workers at most 0.75x the
time of 1 on 2 cores. A control (a CPU-bound loop split over two processes)
shows what the two cores give while the benchmark runs. Run::

    python benchmarks/bench_evaluate.py                    # 200 projected runs, 4 physics runs
    python benchmarks/bench_evaluate.py --repeats 15 --physics-runs 8

Each "run" is one run of both plans (the original and the transformed one).
"""
from __future__ import annotations

import statistics
import time
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent


def _runs_phase(study, problem, applied, runs, runner) -> float:
    from htn.evaluation.study import run_study
    return run_study(study, problem, applied, runs, 0, runner).seconds


def _projected(problem: str, runs: int, repeats: int) -> list:
    """Runs-phase times of (1 worker, 2 workers), measured in turn, pair by
    pair, so that a machine whose speed drifts moves both alike."""
    from htn.evaluation.cluster import InProcess, open_runner
    from htn.evaluation.study import prepare_study
    study, applied = prepare_study(str(ROOT / "domains" / "kitchen.jshop"), problem)
    one = InProcess()
    started = time.perf_counter()
    with open_runner(2) as two:
        up = time.perf_counter() - started
        first = [_runs_phase(study, problem, applied, runs, r) for r in (one, two)]
        pairs = [tuple(_runs_phase(study, problem, applied, runs, r) for r in (one, two))
                 for _ in range(repeats)]
    click.echo(f"  local cluster of 2 workers started in {up:.2f} s; first evaluation "
               f"(fresh workers prepare the study): 1 worker {first[0]:.3f} s, "
               f"2 workers {first[1]:.3f} s")
    for i, label in enumerate(("1 worker (this process)", "2 workers (Dask)")):
        times = [p[i] for p in pairs]
        click.echo(f"  {label}: median {statistics.median(times):.3f} s "
                   f"(min {min(times):.3f}, max {max(times):.3f}, {repeats} repeats)")
    return pairs


def _spin(n: int) -> int:
    total = 0
    for i in range(n):
        total += i * i
    return total


def _control(repeats: int, n: int = 4_000_000) -> None:
    """What two cores give right now: a pure-Python loop in one process
    against its two halves in two (about 0.5 on two idle cores; other work
    on the machine pushes it towards 1)."""
    from concurrent.futures import ProcessPoolExecutor
    ratios = []
    with ProcessPoolExecutor(2) as pool:
        list(pool.map(_spin, [10, 10]))
        for _ in range(repeats):
            t0 = time.perf_counter()
            _spin(n)
            t1 = time.perf_counter()
            list(pool.map(_spin, [n // 2, n // 2]))
            ratios.append((time.perf_counter() - t1) / (t1 - t0))
    click.echo(f"  control, a CPU-bound loop split over 2 processes / 1 process: median "
               f"{statistics.median(ratios):.2f}x (min {min(ratios):.2f}x, max {max(ratios):.2f}x)")


def _physics(problem: str, runs: int) -> None:
    from htn.evaluation.cluster import open_runner
    from htn.evaluation.study import prepare_study
    study, applied = prepare_study(str(ROOT / "domains" / "kitchen.jshop"), problem,
                                   robot="pybullet")
    for workers in (1, 2):
        with open_runner(workers) as runner:
            seconds = _runs_phase(study, problem, applied, runs, runner)
        executions = runs * len(study.plans)
        click.echo(f"  {workers} worker(s): {executions} physics runs in {seconds:.1f} s = "
                   f"{executions / seconds * 60:.1f} runs per minute")


@click.command()
@click.option("--problem", default="transport_four", show_default=True)
@click.option("--runs", default=200, show_default=True, help="Projected runs of each plan.")
@click.option("--repeats", default=9, show_default=True)
@click.option("--physics-runs", default=4, show_default=True,
              help="PyBullet runs of each plan (0: skip).")
def main(problem, runs, repeats, physics_runs):
    """Time projected runs on 1 and 2 workers; count physics runs per minute."""
    path = str(ROOT / "problems" / f"{problem}.jshop")
    click.echo(f"{runs} projected runs of each plan of {problem}:")
    pairs = _projected(path, runs, repeats)
    ratios = sorted(two / one for one, two in pairs)
    click.echo(f"  2 workers / 1 worker, pair by pair: median {statistics.median(ratios):.2f}x "
               f"(min {ratios[0]:.2f}x, max {ratios[-1]:.2f}x; target <= 0.75x)")
    _control(repeats)
    if physics_runs:
        click.echo(f"{physics_runs} PyBullet runs of each plan of {problem}:")
        _physics(path, physics_runs)


if __name__ == "__main__":
    main()
