"""``htn validate DOMAIN PROBLEM PLAN``: replay plans from the initial state."""

from __future__ import annotations

import sys

import click

from .options import TIMEOUT_HELP, Count, Timeout, current_stops


@click.command("validate")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.argument("plan_file", metavar="PLAN", type=click.Path(dir_okay=False))
@click.option(
    "--plan-index",
    type=Count(),
    metavar="N",
    help="Validate only the N-th plan of the file [default: every plan].",
)
@click.option(
    "--functions",
    type=click.Path(dir_okay=False),
    metavar="FILE.py",
    help="Python file with user functions for (call ...).",
)
@click.option("--timeout", type=Timeout(), metavar="SECONDS", help=TIMEOUT_HELP)
@click.option("-q", "--quiet", is_flag=True, help="Print only failures.")
def validate(domain, problem, plan_file, plan_index, functions, timeout, quiet):
    """Check that each plan in PLAN can be executed from PROBLEM's initial
    state with DOMAIN's operators: every step's precondition holds in the
    state its predecessors reach, no step deletes a protected atom, and the
    plan's cost is the sum of its steps' costs.

    A plan in the IPC 2020 format (`htn plan -f ipc`, `==>` ... `<==`) is
    checked as the competition's verifier does: also every decomposition
    line (the method exists for its task, its parameters and precondition
    hold where it is applied, its subtasks are the listed ids in an order it
    allows), every action reached from the root exactly once, the root tasks
    the problem's initial task network, and the goal.

    Exit code 0 when every plan is valid, 1 when one is not (the first step
    that fails is printed as PLAN:line:col), 2 for bad input.

    \b
    Examples:
      htn plan DOMAIN PROBLEM -o plan.txt && htn validate DOMAIN PROBLEM plan.txt
      htn validate basic problem plans-all.txt
    """
    from htn.api.validate import ipc_text
    from htn.api.validate import validate as validate_plans
    from htn.process import deadline

    stops = current_stops()
    with deadline(stops, timeout, stops.started):
        text = ipc_text(plan_file)
        if text is not None:
            sys.exit(
                _validate_ipc(domain, problem, plan_file, text, plan_index, functions, quiet, stops)
            )
        checked = validate_plans(
            domain, problem, plan_file, plan_index=plan_index, functions=functions, stops=stops
        )
    bad = 0
    for c in checked:
        label = f"plan {c.plan.index + 1}"
        if c.valid:
            if not quiet:
                click.echo(f"{label}: valid, {c.verdict.steps} steps, cost {c.plan.cost:g}")
            continue
        bad += 1
        step = f", step {c.failed_step}" if c.failed_step is not None else ""
        click.echo(f"{c.where}: {label}{step}: {c.verdict.reason}", err=True)
    if len(checked) > 1 and not quiet:
        click.echo(f"{len(checked) - bad} of {len(checked)} plans valid")
    sys.exit(1 if bad else 0)


def _validate_ipc(domain, problem, plan_file, text, plan_index, functions, quiet, stops) -> int:
    from htn.api.validate import validate_ipc

    results = validate_ipc(
        domain,
        problem,
        plan_file,
        plan_index=plan_index,
        functions=functions,
        text=text,
        stops=stops,
    )
    bad = 0
    for p, verdict in results:
        label = f"plan {p.index + 1}"
        if verdict.valid:
            if not quiet:
                click.echo(
                    f"{label}: valid, {verdict.actions} actions, "
                    f"{verdict.decompositions} decompositions"
                )
            continue
        bad += 1
        for f in verdict.findings[:10]:
            click.echo(f"{plan_file}:{f.line}:{f.col}: {label}: {f.message}", err=True)
        if len(verdict.findings) > 10:
            click.echo(f"{plan_file}: {label}: ... and {len(verdict.findings) - 10} more", err=True)
    if len(results) > 1 and not quiet:
        click.echo(f"{len(results) - bad} of {len(results)} plans valid")
    return 1 if bad else 0
