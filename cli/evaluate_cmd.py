"""``htn evaluate PROBLEM``: projected runs with and without transformation."""
from __future__ import annotations

import json
import os

import click

from htn.jshop.errors import HtnError


def _domain_for(problem: str) -> str:
    """The problem's domain file: ../domains/NAME.jshop beside it, domains/
    here, or the bundled one of that name."""
    from htn import EXAMPLES
    from htn.jshop.parser import load_problem
    name = load_problem(problem).domain_name
    for base in (os.path.join(os.path.dirname(os.path.abspath(problem)), "..", "domains"),
                 "domains", str(EXAMPLES / "domains")):
        path = os.path.normpath(os.path.join(base, f"{name}.jshop"))
        if os.path.isfile(path):
            return path
    raise HtnError(f"cannot find the domain file {name}.jshop; give it with --domain", problem)


@click.command("evaluate")
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("--domain", type=click.Path(dir_okay=False),
              help="Domain file [default: ../domains/<domain name>.jshop beside PROBLEM].")
@click.option("--runs", type=click.IntRange(min=2), default=200, show_default=True,
              help="Projected runs of each plan.")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the first run.")
@click.option("--workers", type=click.IntRange(min=1), default=1, show_default=True,
              help="Worker processes.")
@click.option("--plot", "plot_dir", type=click.Path(file_okay=False), metavar="DIR",
              help="Write PNG plots of the metrics (like the paper's Fig. 8 and 9).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def evaluate(problem, domain, runs, seed, workers, plot_dir, as_json):
    """Project PROBLEM's plan and its transformed plan RUNS times each and
    compare navigation distance, manipulation cost, actions and failure rate
    (mean, standard deviation, change, Welch t-test p-value).

    \b
    Example:
      htn evaluate problems/transport_four.jshop --runs 200 --plot plots/
    """
    from rich.console import Console
    from rich.progress import Progress

    from .extras import require_extra
    require_extra("eval", "htn evaluate")
    from htn.transform.evaluate import METRIC_NAMES, compare, plot

    if not os.path.isfile(problem):
        raise HtnError("no such file", problem)
    domain = domain or _domain_for(problem)
    console = Console(stderr=True)
    with Progress(console=console, transient=True, disable=as_json and not console.is_terminal) as bar:
        task = bar.add_task("projecting", total=runs)
        comp = compare(domain, problem, runs, seed, workers,
                       progress=lambda: bar.advance(task))
    stats = comp.metrics()
    plots = plot(comp, plot_dir) if plot_dir else []
    if as_json:
        click.echo(json.dumps({"problem": problem, "runs": runs, "applied": comp.applied,
                               "metrics": stats, "plots": plots}, indent=1))
        return
    from rich.table import Table
    t = Table(title=f"{os.path.basename(problem)}: {runs} projected runs each; applied: "
                    f"{', '.join(comp.applied) or 'none'}")
    for col in ("metric", "original mean ± sd", "transformed mean ± sd", "change", "p (Welch)"):
        t.add_column(col, justify="left" if col == "metric" else "right")
    for name in METRIC_NAMES:
        s = stats[name]
        fmt = "{:.1%}" if name == "failures" else "{:.2f}"
        t.add_row(name,
                  f"{fmt.format(s['original']['mean'])} ± {fmt.format(s['original']['sd'])}",
                  f"{fmt.format(s['transformed']['mean'])} ± {fmt.format(s['transformed']['sd'])}",
                  f"{s['change_pct']:+.1f}%", f"{s['p_value']:.2g}")
    Console().print(t)
    for path in plots:
        click.echo(f"plot: {path}")
