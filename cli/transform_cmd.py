"""``htn transform DOMAIN PROBLEM``: apply plan transformations to a plan's task tree."""

from __future__ import annotations

import json
import sys

import click

from htn.process import deadline

from .options import TIMEOUT_HELP, Timeout, current_stops
from .output import warn
from .progress import Phase


@click.command("transform")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option(
    "--rules",
    metavar="NAME,...",
    help="Only these transformations (default: all registered: tray, container, both-hands).",
)
@click.option(
    "--metric",
    type=click.Choice(["navigation", "manipulation", "actions", "navigation-static"]),
    default="navigation",
    show_default=True,
    help="A transformation that makes this worse (mean over 64 projected runs; "
    "navigation-static: distance between area centres) is rolled back.",
)
@click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False),
    help="Write the transformed plan (jshop format with header, rewritten task list and "
    "task tree) for 'htn run'.",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
@click.option(
    "--timeout",
    type=Timeout(),
    metavar="SECONDS",
    help=TIMEOUT_HELP + " -o is written only if all is done in time.",
)
def transform(domain, problem, rules, metric, output, as_json, timeout):
    """Plan PROBLEM, transform its task tree with the registered rules
    (tray > container > both-hands), check and print what changed.

    \b
    Every transformed plan is re-planned from the rewritten task list, so each
    step's precondition holds in sequence from the initial state; a rewrite
    that breaks the plan or costs more on --metric is rolled back.
    """
    from htn.api.transform import UnknownRules, transform_plan

    # a bad -o fails before the work; the file is replaced once all is done
    try:
        # planning and each rule's projected runs take seconds: a spinner
        # says which (on a terminal, after a second)
        stops = current_stops()
        with (
            deadline(stops, timeout, stops.started),
            Phase("reading the domain and the problem") as phase,
        ):
            done = transform_plan(
                domain,
                problem,
                rules=rules,
                metric=metric,
                on_warning=warn,
                on_phase=phase.update,
                stops=stops,
                output=output,
            )
    except UnknownRules as exc:
        raise click.BadParameter(exc.message, param_hint="--rules") from None
    result = done.document
    if as_json:
        click.echo(json.dumps(result, indent=1))
        return
    for entry in result["log"]:
        mark = "+" if entry["status"] == "applied" else "-"
        click.echo(f"{mark} {entry['rule']:<11} {entry['status']:<12} {entry['detail']}")
    if not result["log"]:
        click.echo("no transformation applies")
    for ch in result["changes"]:
        click.echo(f"\n{ch['rule']}: {' , '.join(ch['paths'])}")
        for t in ch["tasks"]:
            click.echo(f"    {t}")
    o, t = result["original"], result["transformed"]
    click.echo(
        f"\nplan: {o['steps']} -> {t['steps']} steps; {metric}: {o[metric]:.2f} -> {t[metric]:.2f}"
    )
    sys.stdout.flush()
