"""Benchmark: ``htn plan --search auto`` costs the same CPU on every run.

The portfolio's turns are slices of this process's CPU time (not of wall
time), so another job on the machine delays a run without changing what it
does in its CPU time; the expansions may still differ a little from run to
run (a slice ends between two expansions). For each instance this runs ``htn plan DOMAIN PROBLEM --search auto
-f json`` ``--runs`` times as fresh processes, every other run while a busy
loop runs on each core (``--load``, on by default: the loaded runs share the
CPU with it), and reports each run's whole-process CPU time (user + system,
from ``wait4``), the largest over the smallest, and whether every run
expanded the same number of nodes and found the plan with the same search.
Run::

    python benchmarks/bench_portfolio.py                   # two ipc-po instances
    python benchmarks/bench_portfolio.py --runs 7 --no-load
    python benchmarks/bench_portfolio.py DOMAIN PROBLEM    # any instance

Target (issue 38): five runs within 20% of each other's CPU time.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import click

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ipc import run_limited  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("HTN_SHARED", ROOT.parent / "shared"))
DEFAULT = [
    ("ipc-po/Transport/domain.hddl", "ipc-po/Transport/pfile04.hddl"),
    (
        "ipc2020-to-hard/Multiarm-Blocksworld/domain.hddl",
        "ipc2020-to-hard/Multiarm-Blocksworld/pfile_02_055.hddl",
    ),
]
HOG = "while True: pass"
LIMIT = 300  # CPU seconds a run may take


def run(domain: str, problem: str) -> dict:
    argv = [sys.executable, "-m", "htn", "plan", domain, problem, "--search", "auto", "-f", "json"]
    r = run_limited(argv, LIMIT)
    stats = json.loads(r["stdout"].splitlines()[-1]) if r["stdout"] else {}
    return {
        "cpu_s": round(r["cpu_s"], 3),
        "exit": r["rc"],
        "expansions": stats.get("expansions"),
        "found_by": stats.get("found_by"),
    }


@click.command()
@click.argument("instance", nargs=-1)
@click.option("--runs", default=5, show_default=True, type=click.IntRange(min=2))
@click.option("--load/--no-load", default=True, show_default=True, help="Load every other run.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of lines.")
def main(instance, runs, load, as_json):
    """Whole-process CPU of --search auto, run after run."""
    pairs = (
        [tuple(instance)]
        if instance
        else [(str(SHARED / "corpus" / d), str(SHARED / "corpus" / p)) for d, p in DEFAULT]
    )
    if any(len(p) != 2 for p in pairs):
        raise click.UsageError("give DOMAIN PROBLEM, or nothing for the default instances")
    report = []
    for domain, problem in pairs:
        rows = []
        for k in range(runs):
            hogs = []
            if load and k % 2 == 1:
                hogs = [
                    subprocess.Popen([sys.executable, "-c", HOG])
                    for _ in range(os.cpu_count() or 1)
                ]
            try:
                rows.append({**run(domain, problem), "loaded": bool(hogs)})
            finally:
                for h in hogs:
                    h.kill()
                    h.wait()
            click.echo(f"{Path(problem).name} run {k + 1}: {rows[-1]}", err=True)
        cpus = [r["cpu_s"] for r in rows]
        report.append(
            {
                "problem": problem,
                "runs": rows,
                "cpu_max_over_min": round(max(cpus) / min(cpus), 3),
                "same_work": len({(r["expansions"], r["found_by"]) for r in rows}) == 1,
            }
        )
    if as_json:
        click.echo(json.dumps(report, indent=1))
        return
    for r in report:
        cpus = ", ".join(f"{x['cpu_s']:.2f}{'*' if x['loaded'] else ''}" for x in r["runs"])
        click.echo(
            f"{Path(r['problem']).name}: CPU s {cpus} (* loaded); max/min {r['cpu_max_over_min']}; "
            f"same expansions and search every run: {r['same_work']} "
            f"({r['runs'][0]['expansions']} expansions, found by {r['runs'][0]['found_by']})"
        )


if __name__ == "__main__":
    main()
