"""``htn stats``: the planning paper's Table 1, for its scenarios or any problem."""

from __future__ import annotations

import json
from pathlib import Path

import click

from htn.process import DeadlineExceeded, deadline

from .options import MAX_RUNS, TIMEOUT_HELP, Count, Timeout, current_stops
from .output import console

GRACE = 0.5  # seconds past --timeout before a user function is interrupted


@click.command("stats")
@click.argument("files", nargs=-1, type=click.Path(dir_okay=False))
@click.option(
    "--repeat",
    type=Count(1, MAX_RUNS),
    default=5,
    show_default=True,
    help="Plan N times and report the median time.",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.option(
    "--functions",
    type=click.Path(dir_okay=False),
    metavar="FILE.py",
    help="Python file with user functions for (call ...).",
)
@click.option(
    "--timeout",
    type=Timeout(),
    metavar="SECONDS",
    help=TIMEOUT_HELP + " An enumeration cut short is reported as partial; the repeats stop then.",
)
def stats(files, repeat, as_json, functions, timeout):
    """Plan counts, planning time, shortest plan and domain size (Table 1).

    \b
    Without arguments: the paper's two scenarios (bring an object, guide a
    robot; the bundled examples, see 'htn examples') with the paper's
    figures beside ours. With arguments: the first is
    a DOMAIN, the rest are PROBLEMs in it:
      htn stats
      htn stats domains/domestic.jshop problems/bring_coke.jshop problems/bring_two.jshop
    """
    if len(files) == 1:
        raise click.UsageError("give a DOMAIN and at least one PROBLEM (or no arguments)")
    rows = _figures(files, repeat, functions, timeout)
    if as_json:
        click.echo(json.dumps({"scenarios": [r.as_dict() for r in rows]}, indent=1))
        return
    out = console()
    out.print(_table(rows, show_paper=not files))
    done = min(r.repeats for r in rows)
    out.print(
        f"[dim]time: median of {done} run(s)"
        + (f" (of {repeat} asked: --timeout ran out)" if done < repeat else "")
        + f"; parsing excluded; domain {rows[0].domain}[/dim]"
    )
    if any(r.timed_out for r in rows):
        out.print("[yellow]some problems timed out; their counts are partial[/yellow]")


def _figures(files, repeat: int, functions, timeout) -> list:
    """Each scenario's figures, its inputs' warnings printed once per domain.
    ``timeout`` bounds the whole command: each enumeration gets what is left
    (the planner stops by itself and the figures are partial), and the
    deadline a little after it catches a user function that never returns,
    which the planner cannot interrupt."""
    from htn.api.inputs import function_table
    from htn.api.stats import scenario_stats, scenarios

    rows: list = []
    shown: set = set()
    stops = current_stops()
    started = stops.started
    until = None if timeout is None else started + timeout
    with deadline(stops, None if timeout is None else timeout + GRACE, started):
        pairs = scenarios(files)
        table = function_table(functions, stops)
        for d, p in pairs:
            try:
                rows.append(scenario_stats(d, p, table, repeat, until=until))
            except DeadlineExceeded:
                click.echo(
                    f"{p}: --timeout {timeout:g} s ran out inside a user function "
                    "or comparator; no figures",
                    err=True,
                )
                raise SystemExit(1) from None
            for w in rows[-1].warnings:
                if w not in shown:
                    shown.add(w)
                    click.echo(w, err=True)
    return rows


def _table(rows: list, show_paper: bool):
    """The figures as a rich table, the paper's beside them for its scenarios."""
    from rich import box
    from rich.table import Table

    from htn.api.stats import PAPER

    t = Table(title="Plan generation (cf. Table 1 of the planning paper)", box=box.ROUNDED)
    t.add_column("", style="bold")
    for r in rows:
        t.add_column(Path(r.problem).stem, justify="right")

    def paper(r, key, fmt="{}"):
        ref = PAPER.get(Path(r.problem).stem) if show_paper else None
        return f"  [dim](paper {fmt.format(ref[key])})[/dim]" if ref else ""

    def sizes(r):
        ref = PAPER.get(Path(r.problem).stem) if show_paper else None
        return f"  [dim](paper {ref['methods']} / {ref['operators']})[/dim]" if ref else ""

    t.add_row("solution plans", *[f"{r.plans}{paper(r, 'plans')}" for r in rows])
    t.add_row(
        "distinct action sequences",
        *[f"{r.distinct_plans}{paper(r, 'distinct_plans')}" for r in rows],
    )
    t.add_row(
        "time to plan (all plans)",
        *[f"{r.plan_ms:.2f} ms{paper(r, 'plan_s', '{:g} s')}" for r in rows],
    )
    t.add_row(
        "minimum plan length",
        *[
            f"{r.min_length if r.min_length is not None else '-'}{paper(r, 'min_length')}"
            for r in rows
        ],
    )
    t.add_row("methods / operators", *[f"{r.methods} / {r.operators}{sizes(r)}" for r in rows])
    return t
