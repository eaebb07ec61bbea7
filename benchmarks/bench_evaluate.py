"""Benchmark: ``htn evaluate`` on 1 and 2 workers, and what starting workers costs.

Three measurements, each of the whole evaluation as ``htn evaluate`` does
it (:func:`htn.api.evaluate.evaluate`: the inputs read and checked, the
plans made and transformed, the runs on 1 or 2 workers, the workers started
and closed when they are: everything but the interpreter's own start-up):

* ``--startup``: starting and closing a local Dask cluster of N workers
  in a fresh process, as ``htn evaluate`` does (what
  :func:`htn.evaluation.cluster.start_seconds` estimates), median of the
  repeats;
* projected runs (default 200 of transport_four) with ``--workers 1`` and
  ``--workers 2``, in turn, pair by pair, so that a machine whose speed
  drifts moves both alike: a study this small stays in one process on two
  workers (the line that says so is shown), so 2 workers should take as
  long as 1, never longer;
* physics runs (``--robot pybullet``, default 20 of each plan) on 1 and 2
  workers: runs per minute of each, and their ratio (target: at least 1.6
  on 2 cores).

A control (a CPU-bound loop split over two processes) shows what the two
cores give while the benchmark runs. Run::

    python benchmarks/bench_evaluate.py                     # all three
    python benchmarks/bench_evaluate.py --physics-runs 0    # no physics
    python benchmarks/bench_evaluate.py --runs 0 --physics-repeats 3
    python benchmarks/bench_evaluate.py --startup --repeats 5 --physics-runs 0 --runs 0

Each "run" is one run of both plans (the original and the transformed one).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent
DOMAIN = str(ROOT / "domains" / "kitchen.jshop")


def _evaluation(problem: str, runs: int, workers: int, robot: str = "projection"):
    """The whole evaluation of ``htn evaluate --workers N``; (seconds, comparison, notes)."""
    from htn.api.evaluate import Progress, evaluate

    class Notes(Progress):  # keeps the line that says why the runs stay in this process
        def __init__(self):
            self.lines: list[str] = []

        def note(self, text: str) -> None:
            self.lines.append(text)

    notes = Notes()
    t0 = time.perf_counter()
    result = evaluate(
        problem, domain=DOMAIN, runs=runs, seed=0, workers=workers, robot=robot, progress=notes
    )
    return time.perf_counter() - t0, result.comparison, notes.lines


# one start in a fresh process, as each htn evaluate is: the first start of a
# process also starts the server the workers are forked from
_START = """
import sys, time
from htn.evaluation.cluster import start_local_cluster
n = int(sys.argv[1])
t0 = time.perf_counter()
cluster, client = start_local_cluster(n)
client.wait_for_workers(n)
t1 = time.perf_counter()
client.close()
cluster.close()
print(t1 - t0, time.perf_counter() - t1)
"""


def _startup(repeats: int, sizes=(1, 2, 4)) -> None:
    import subprocess
    import sys

    from htn.evaluation.cluster import start_seconds

    for n in sizes:
        starts, closes = [], []
        for _ in range(repeats):
            out = subprocess.run(
                [sys.executable, "-c", _START, str(n)], capture_output=True, text=True, check=True
            ).stdout.split()
            starts.append(float(out[0]))
            closes.append(float(out[1]))
        click.echo(
            f"  {n} worker(s): start median {statistics.median(starts):.2f} s "
            f"(min {min(starts):.2f}, max {max(starts):.2f}), close median "
            f"{statistics.median(closes):.2f} s; together "
            f"{statistics.median(starts) + statistics.median(closes):.2f} s "
            f"(htn's estimate: {start_seconds(n):.2f} s)"
        )


def _projected(problem: str, runs: int, repeats: int) -> None:
    pairs, shown = [], set()
    for i in range(repeats + 1):
        pair = []
        for workers in (1, 2):
            seconds, comp, notes = _evaluation(problem, runs, workers)
            pair.append((seconds, comp))
            for note in notes:
                if note not in shown:
                    shown.add(note)
                    click.echo(f"  (2 workers said) {note}")
        if i:  # the first pair warms the caches: not counted
            pairs.append(pair)
    assert all(a[1].metrics() == b[1].metrics() for a, b in pairs), "metrics differ"
    for k, label in enumerate(("--workers 1", "--workers 2")):
        times = [p[k][0] for p in pairs]
        click.echo(
            f"  {label}: median {statistics.median(times):.3f} s "
            f"(min {min(times):.3f}, max {max(times):.3f}, {repeats} repeats; "
            f"ran on {pairs[0][k][1].workers} process(es))"
        )
    ratios = sorted(b[0] / a[0] for a, b in pairs)
    click.echo(
        f"  2 workers / 1 worker, pair by pair: median {statistics.median(ratios):.2f}x "
        f"(min {ratios[0]:.2f}x, max {ratios[-1]:.2f}x; target <= 1.0x)"
    )


def _physics(problem: str, runs: int, repeats: int) -> None:
    """Physics runs per minute on 1 and 2 workers, ``repeats`` pairs in
    turn (the machine's speed drifts: a pair sees about the same)."""
    ratios, results = [], []
    for _ in range(repeats):
        rates = {}
        for workers in (1, 2):
            seconds, comp, notes = _evaluation(problem, runs, workers, robot="pybullet")
            for note in notes:
                click.echo(f"  ({workers} workers said) {note}")
            executions = runs * 2
            rates[workers] = executions / seconds * 60
            results.append(comp.metrics())
            click.echo(
                f"  --workers {workers}: {executions} physics runs in {seconds:.1f} s = "
                f"{rates[workers]:.1f} runs per minute (ran on {comp.workers} "
                f"process(es))"
            )
        ratios.append(rates[2] / rates[1])
        click.echo(f"  2 workers / 1 worker: {ratios[-1]:.2f}x the runs per minute")
    click.echo(
        f"  pair by pair: median {statistics.median(ratios):.2f}x (min {min(ratios):.2f}x, "
        f"max {max(ratios):.2f}x; target >= 1.6x); the same metrics: "
        f"{all(m == results[0] for m in results)}"
    )


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
    click.echo(
        f"  control, a CPU-bound loop split over 2 processes / 1 process: median "
        f"{statistics.median(ratios):.2f}x (min {min(ratios):.2f}x, max {max(ratios):.2f}x)"
    )


@click.command()
@click.option("--problem", default="transport_four", show_default=True)
@click.option(
    "--runs", default=200, show_default=True, help="Projected runs of each plan (0: skip)."
)
@click.option("--repeats", default=9, show_default=True)
@click.option(
    "--physics-runs", default=20, show_default=True, help="PyBullet runs of each plan (0: skip)."
)
@click.option(
    "--physics-repeats",
    default=1,
    show_default=True,
    help="Pairs of physics evaluations (1 and 2 workers).",
)
@click.option("--startup", is_flag=True, help="Also time starting local clusters of 1, 2, 4.")
def main(problem, runs, repeats, physics_runs, physics_repeats, startup):
    """Time evaluations on 1 and 2 workers; count physics runs per minute."""
    path = str(ROOT / "problems" / f"{problem}.jshop")
    if startup:
        click.echo("starting and closing a local Dask cluster:")
        _startup(repeats)
    if runs:
        click.echo(f"{runs} projected runs of each plan of {problem}, the whole evaluation:")
        _projected(path, runs, repeats)
        _control(repeats)
    if physics_runs:
        click.echo(f"{physics_runs} PyBullet runs of each plan of {problem}, the whole evaluation:")
        _physics(path, physics_runs, physics_repeats)
        _control(repeats)


if __name__ == "__main__":
    main()
