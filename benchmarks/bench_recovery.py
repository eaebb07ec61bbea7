"""Benchmark: how often a run recovers from injected faults, with and without
``--replan`` (repair in the task tree), in the PyBullet simulation (DIRECT).

Each run is what ``htn run PLAN --sim --faults F --seed S [--replan]`` does,
in worker processes. Reports successes per configuration, the repaired node
paths, and aborts unexplained by the simulator (false alarms: an ``aborted``
event although the step's effect and the hold-monitor's condition hold)::

    python benchmarks/bench_recovery.py                       # the issue's figures
    python benchmarks/bench_recovery.py --problem bring_object --faults moved=1 --runs 20 --replan
"""

from __future__ import annotations

import multiprocessing
import sys
import time
from collections import Counter
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

DEFAULT = [  # (problem, faults, runs, replan)
    ("bring_object", "moved=1", 20, True),
    ("transport_four", "moved=1", 10, True),
    ("bring_object", "slip=0.3,nav=0.3,detect=0.3,moved=0.3", 50, False),
    ("bring_object", "slip=0.3,nav=0.3,detect=0.3,moved=0.3", 50, True),
]


def one(job):
    from monitoring_oracle import run_checked

    problem, faults, seed, replan = job
    return run_checked(problem, faults, seed, replan)


@click.command()
@click.option("--problem", help="One configuration: this problem (default: the issue's set).")
@click.option("--faults", default="moved=1", show_default=True)
@click.option("--runs", default=20, show_default=True)
@click.option("--replan", is_flag=True)
@click.option("--workers", default=2, show_default=True)
def main(problem, faults, runs, replan, workers):
    """Success rates under faults, with and without repair."""
    configs = [(problem, faults, runs, replan)] if problem else DEFAULT
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(workers) as pool:
        for prob, flt, n, rep in configs:
            t0 = time.perf_counter()
            results = pool.map(one, [(prob, flt, seed, rep) for seed in range(n)])
            ok = sum(r["result"] == "verified" for r in results)
            paths = Counter(p for r in results for p in r["repaired"])
            unexplained = [a for r in results for a in r["false_alarms"]]
            click.echo(
                f"{prob} --faults {flt} {'--replan' if rep else '(no replan)'}: "
                f"{ok}/{n} verified; {sum(r['aborts'] for r in results)} aborted events, "
                f"{len(unexplained)} unexplained; {sum(r['faults'] for r in results)} "
                f"faults; {time.perf_counter() - t0:.1f} s"
            )
            if paths:
                click.echo(
                    "    repaired: " + ", ".join(f"{p} x{c}" for p, c in paths.most_common())
                )
            for a in unexplained[:5]:
                click.echo(f"    FALSE ALARM: {a}")


if __name__ == "__main__":
    main()
