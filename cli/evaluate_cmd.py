"""``htn evaluate PROBLEM``: runs of a plan with and without transformation,
on one process, a local Dask cluster or an existing one."""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING

import click

from htn.api.evaluate import (
    METRIC_NAMES,
    ClusterError,
    EvaluateOptions,
    Progress,
    format_change,
    format_p,
)
from htn.api.evaluate import evaluate as run_evaluation
from htn.process import deadline

from .options import MAX_RUNS, MAX_WORKERS, SEED, TIMEOUT_HELP, Count, Timeout, current_stops
from .output import warn
from .progress import Phase

if TYPE_CHECKING:
    from rich.progress import TaskID


@click.command("evaluate")
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--domain",
    type=click.Path(dir_okay=False),
    help="Domain file [default: <domain name>.jshop, or the file that defines that "
    "domain, beside PROBLEM, in ../domains/ beside it, in ./domains/, or the "
    "bundled one].",
)
@click.option(
    "--runs", type=Count(1, MAX_RUNS), default=200, show_default=True, help="Runs of each plan."
)
@click.option(
    "--seed",
    type=SEED,
    default=0,
    show_default=True,
    help="Seed of the first run (run i uses seed + i, for both plans).",
)
@click.option(
    "--robot",
    default="projection",
    show_default=True,
    metavar="NAME",
    help="Robot the runs execute on: 'projection' (the paper's fast kinematic "
    "projection) or 'pybullet' (the physics robot; the 'sim' extra).",
)
@click.option(
    "--faults",
    default="",
    metavar="KIND=P,...",
    help="Failure probabilities. projection: navigate, detect, grasp, grasp_busy, "
    "place, container, tray (defaults 0.02-0.10; given ones replace them); "
    "pybullet: slip, nav, detect, moved (default none).",
)
@click.option(
    "--workers",
    type=Count(1, MAX_WORKERS),
    default=None,
    metavar="N",
    help="Worker processes: 1 runs in this process, more start a local Dask cluster  [default: 1]",
)
@click.option(
    "--scheduler",
    metavar="tcp://HOST:PORT",
    help="Run on an existing Dask cluster (dask scheduler / dask worker, SSH, "
    "SLURM, Kubernetes); its scheduler and workers need htn installed.",
)
@click.option(
    "--records",
    type=click.Path(),
    metavar="FILE",
    help="Write one JSON line per run of each plan (streamed as runs finish; in "
    "run order when all are done).",
)
@click.option(
    "--plot",
    "plot_dir",
    type=click.Path(),
    metavar="DIR",
    help="Write figures as PNG (300 dpi), PDF and SVG (like the paper's Fig. 8, 9).",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option(
    "--timeout",
    type=Timeout(),
    metavar="SECONDS",
    help=TIMEOUT_HELP + " Planning, transforming and the runs: what ends "
    "unfinished prints no table, and --records keeps the runs done.",
)
def evaluate(problem, domain, plot_dir, as_json, timeout, **settings):
    """Execute PROBLEM's plan and its transformed plan RUNS times each and
    compare navigation, manipulation, actions and failure rate (mean,
    standard deviation, change, Welch t-test p-value; pooled failure
    proportion with a Wilson 95% interval). The metrics for a seed are the
    same on any number of workers.

    \b
    Examples:
      htn evaluate problems/transport_four.jshop --runs 200 --plot plots/
      htn evaluate problems/tray_three.jshop --workers 2 --records runs.jsonl
      htn evaluate problems/tray_three.jshop --robot pybullet --faults slip=0.1 --runs 20
      htn evaluate problems/tray_three.jshop --scheduler tcp://10.0.0.5:8786
    """
    # runs, seed, robot, faults, workers, scheduler and records, as named
    options = EvaluateOptions(**settings, plot=plot_dir)
    progress = _Progress(options.robot, options.runs)
    stops = current_stops()
    try:
        with deadline(stops, timeout, stops.started), progress.spinner:
            result = run_evaluation(problem, options, domain=domain, progress=progress)
    except ClusterError as exc:
        raise click.ClickException(str(exc)) from None
    finally:
        progress.stop()
    if as_json:
        click.echo(json.dumps(result.document(), indent=1))
        return
    _print_table(result, problem)
    for path in result.plots:
        click.echo(f"plot: {path}")


class _Progress(Progress):
    """What a terminal shows while an evaluation runs: a spinner naming what
    runs before the runs (reading, planning, each rule's projections), then
    a bar of the runs (on stderr; nothing when it is not a terminal); the
    cluster's notes, the evaluation's notes and warnings as lines on stderr."""

    def __init__(self, robot: str, runs: int):
        from rich.console import Console
        from rich.progress import Progress as Bar

        console = Console(stderr=True)
        self.bar = Bar(console=console, transient=True, disable=not console.is_terminal)
        self.task: TaskID | None = None
        self.spinner = Phase("starting")
        self.robot, self.runs = robot, runs
        self.label = f"{robot} runs"

    def started(self, workers: int, notes: list) -> None:
        for note in notes:
            warn(f"warning: {note}")
        self.label = f"{self.robot} runs on {workers} worker(s)"

    def phase(self, text: str) -> None:
        self.spinner.update(text)

    def batch(self, records: list, runs: float) -> None:
        if self.task is None:  # the first runs are in: the bar replaces the spinner
            self.spinner.end()
            self.task = self.bar.add_task(self.label, total=self.runs)
            self.bar.start()
        self.bar.advance(self.task, runs)

    def note(self, text: str) -> None:
        warn(text)

    def warning(self, text: str) -> None:
        warn(text)

    def stop(self) -> None:
        self.bar.stop()


def _print_table(result, problem: str) -> None:
    from rich.console import Console
    from rich.table import Table

    stats = result.metrics

    def cell(value, fmt: str) -> str:
        return "n/a" if value is None else fmt.format(value)

    t = Table(
        title=f"{os.path.basename(problem)}: {result.heading()}",
        caption="mean \u00b1 SD over runs; p: Welch's two-sided t-test",
    )
    for col in (
        "metric",
        "original mean \u00b1 sd",
        "transformed mean \u00b1 sd",
        "change",
        "p (Welch)",
    ):
        t.add_column(col, justify="left" if col == "metric" else "right")
    for name in METRIC_NAMES:
        s = stats[name]
        fmt = "{:.1%}" if name == "failures" else "{:.2f}"
        t.add_row(
            name,
            *[
                f"{cell(s[side]['mean'], fmt)} \u00b1 {cell(s[side]['sd'], fmt)}"
                for side in ("original", "transformed")
            ],
            format_change(s["change_pct"]),
            format_p(s["p_value"]),
        )
    out = Console()
    out.print(t)
    _print_summary(out, result, cell)


def _print_summary(out, result, cell) -> None:
    comp, stats = result.comparison, result.metrics
    pooled = [stats["failures"][side] for side in ("original", "transformed")]
    out.print(
        "failed / attempted actions, pooled (Wilson 95% CI): "
        + " \u2192 ".join(
            f"{p['failed']}/{p['attempts']} = {cell(p['rate'], '{:.1%}')}"
            + (f" [{p['wilson95'][0]:.1%}, {p['wilson95'][1]:.1%}]" if p["wilson95"] else "")
            for p in pooled
        )
    )
    out.print(
        "runs ended: "
        + " \u2192 ".join(
            ", ".join(f"{n} {result}" for result, n in sorted(ended.items()))
            for ended in comp.results().values()
        )
    )
    done = len(comp.original) + len(comp.transformed)
    out.print(
        f"{done} runs in {comp.seconds:.1f} s ({comp.runs_per_s:.1f} runs/s) on "
        f"{comp.workers} worker(s)"
    )
