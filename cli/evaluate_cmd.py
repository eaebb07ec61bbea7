"""``htn evaluate PROBLEM``: runs of a plan with and without transformation,
on one process, a local Dask cluster or an existing one."""
from __future__ import annotations

import json
import os

import click

from htn.jshop.language.errors import HtnError

from .extras import require_extra, require_robot_extra
from .output import check_output_file, check_output_folder, make_output_folder, warn


def _domain_for(problem: str) -> str:
    """The problem's domain file: ../domains/NAME.jshop beside it, domains/
    here, or the bundled one of that name."""
    from htn import EXAMPLES
    from htn.jshop.readers.load import load_problem
    name = load_problem(problem).domain_name
    for base in (os.path.join(os.path.dirname(os.path.abspath(problem)), "..", "domains"),
                 "domains", str(EXAMPLES / "domains")):
        path = os.path.normpath(os.path.join(base, f"{name}.jshop"))
        if os.path.isfile(path):
            return path
    raise HtnError(f"cannot find the domain file {name}.jshop; give it with --domain", problem)


def _check_options(problem, domain, robot, faults, workers, scheduler, plot_dir, records):
    """Every input and output option, before any work starts (the scheduler's
    address is checked where it is used, by ``open_runner``; nothing is
    written before that)."""
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
    if plot_dir is not None:
        check_output_folder(plot_dir, "--plot")
    if records is not None:
        check_output_file(records, "--records")


@click.command("evaluate")
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("--domain", type=click.Path(dir_okay=False),
              help="Domain file [default: ../domains/<domain name>.jshop beside PROBLEM].")
@click.option("--runs", type=click.IntRange(min=1), default=200, show_default=True,
              help="Runs of each plan.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the first run (run i uses seed + i, for both plans).")
@click.option("--robot", default="projection", show_default=True, metavar="NAME",
              help="Robot the runs execute on: 'projection' (the paper's fast kinematic "
                   "projection) or 'pybullet' (the physics robot; the 'sim' extra).")
@click.option("--faults", default="", metavar="KIND=P,...",
              help="Failure probabilities. projection: navigate, detect, grasp, grasp_busy, "
                   "place, container, tray (defaults 0.02-0.10; given ones replace them); "
                   "pybullet: slip, nav, detect, moved (default none).")
@click.option("--workers", type=click.IntRange(min=1), default=None, metavar="N",
              help="Worker processes: 1 runs in this process, more start a local Dask "
                   "cluster  [default: 1]")
@click.option("--scheduler", metavar="tcp://HOST:PORT",
              help="Run on an existing Dask cluster (dask scheduler / dask worker, SSH, "
                   "SLURM, Kubernetes); its scheduler and workers need htn installed.")
@click.option("--records", type=click.Path(), metavar="FILE",
              help="Write one JSON line per run of each plan (streamed as runs finish; in "
                   "run order when all are done).")
@click.option("--plot", "plot_dir", type=click.Path(), metavar="DIR",
              help="Write figures as PNG (300 dpi), PDF and SVG (like the paper's Fig. 8, 9).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def evaluate(problem, domain, runs, seed, robot, faults, workers, scheduler, records,
             plot_dir, as_json):
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
    _check_options(problem, domain, robot, faults, workers, scheduler, plot_dir, records)
    domain = domain or _domain_for(problem)

    from rich.console import Console
    from rich.progress import Progress

    from htn.evaluation.cluster import ClusterError, open_runner
    from htn.evaluation.study import RecordsFile, plot, prepare_study, run_study

    console = Console(stderr=True)
    stream = None
    try:
        with open_runner(workers or 1, scheduler) as runner:
            if plot_dir is not None:    # all options are checked now (the scheduler last)
                make_output_folder(plot_dir, "--plot")
            for note in runner.notes:
                warn(f"warning: {note}")
            study, applied = prepare_study(domain, problem, robot, faults)
            stream = RecordsFile(records) if records else None
            with Progress(console=console, transient=True,
                          disable=not console.is_terminal) as bar:
                task = bar.add_task(f"{robot} runs on {runner.workers} worker(s)", total=runs)

                def on_batch(new: list) -> None:
                    bar.advance(task, len(new) / len(study.plans))
                    if stream:
                        stream.write(new)

                comp = run_study(study, problem, applied, runs, seed, runner, on_batch, say=warn)
    except ClusterError as exc:
        raise click.ClickException(str(exc)) from None
    finally:
        if stream:
            stream.close()
    if stream:
        stream.finish(comp)
    stats = comp.metrics()
    plots = plot(comp, plot_dir) if plot_dir else []
    if as_json:
        click.echo(json.dumps({"problem": problem, "runs": runs, "applied": comp.applied,
                               "metrics": stats, "plots": plots, "robot": robot,
                               "results": comp.results(), "workers": comp.workers,
                               "runs_per_s": round(comp.runs_per_s, 3)}, indent=1))
        return
    _print_table(comp, stats, problem)
    for path in plots:
        click.echo(f"plot: {path}")


def _print_table(comp, stats: dict, problem: str) -> None:
    from rich.console import Console
    from rich.table import Table

    from htn.evaluation.runs import MEASURES
    from htn.evaluation.statistics import METRIC_NAMES, applied_rules, format_change, format_p

    def cell(value, fmt: str) -> str:
        return "n/a" if value is None else fmt.format(value)

    t = Table(title=f"{os.path.basename(problem)}: {comp.runs} "
                    f"{MEASURES[comp.robot].description} run{'s' if comp.runs > 1 else ''} "
                    f"of each plan; applied: {applied_rules(comp.applied)}",
              caption="mean \u00b1 SD over runs; p: Welch's two-sided t-test")
    for col in ("metric", "original mean \u00b1 sd", "transformed mean \u00b1 sd", "change",
                "p (Welch)"):
        t.add_column(col, justify="left" if col == "metric" else "right")
    for name in METRIC_NAMES:
        s = stats[name]
        fmt = "{:.1%}" if name == "failures" else "{:.2f}"
        t.add_row(name, *[f"{cell(s[side]['mean'], fmt)} \u00b1 {cell(s[side]['sd'], fmt)}"
                          for side in ("original", "transformed")],
                  format_change(s["change_pct"]), format_p(s["p_value"]))
    out = Console()
    out.print(t)
    pooled = [stats["failures"][side] for side in ("original", "transformed")]
    out.print("failed / attempted actions, pooled (Wilson 95% CI): " + " \u2192 ".join(
        f"{p['failed']}/{p['attempts']} = {cell(p['rate'], '{:.1%}')}"
        + (f" [{p['wilson95'][0]:.1%}, {p['wilson95'][1]:.1%}]" if p["wilson95"] else "")
        for p in pooled))
    out.print("runs ended: " + " \u2192 ".join(
        ", ".join(f"{n} {result}" for result, n in sorted(ended.items()))
        for ended in comp.results().values()))
    done = len(comp.original) + len(comp.transformed)
    out.print(f"{done} runs in {comp.seconds:.1f} s ({comp.runs_per_s:.1f} runs/s) on "
              f"{comp.workers} worker(s)")
