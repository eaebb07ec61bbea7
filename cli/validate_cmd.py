"""``htn validate DOMAIN PROBLEM PLAN``: replay plans from the initial state."""
from __future__ import annotations

import sys

import click

from .options import TIMEOUT_HELP, Timeout


@click.command("validate")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.argument("plan_file", metavar="PLAN", type=click.Path(dir_okay=False))
@click.option("--plan-index", type=click.IntRange(min=1), metavar="N",
              help="Validate only the N-th plan of the file [default: every plan].")
@click.option("--functions", type=click.Path(dir_okay=False), metavar="FILE.py",
              help="Python file with user functions for (call ...).")
@click.option("--timeout", type=Timeout(), metavar="SECONDS", help=TIMEOUT_HELP)
@click.option("-q", "--quiet", is_flag=True, help="Print only failures.")
def validate(domain, problem, plan_file, plan_index, functions, timeout, quiet):
    """Check that each plan in PLAN can be executed from PROBLEM's initial
    state with DOMAIN's operators: every step's precondition holds in the
    state its predecessors reach, no step deletes a protected atom, and the
    plan's cost is the sum of its steps' costs.

    Exit code 0 when every plan is valid, 1 when one is not (the first step
    that fails is printed as PLAN:line:col), 2 for bad input.

    \b
    Examples:
      htn plan DOMAIN PROBLEM -o plan.txt && htn validate DOMAIN PROBLEM plan.txt
      htn validate basic problem plans-all.txt
    """
    from htn.api.validate import validate as validate_plans

    from .signals import STATE, deadline
    with deadline(timeout, STATE.started):
        checked = validate_plans(domain, problem, plan_file, plan_index=plan_index,
                                 functions=functions)
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
