"""``htn validate DOMAIN PROBLEM PLAN``: replay plans from the initial state."""
from __future__ import annotations

import sys

import click


@click.command("validate")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.argument("plan_file", metavar="PLAN", type=click.Path(dir_okay=False))
@click.option("--plan-index", type=click.IntRange(min=1), metavar="N",
              help="Validate only the N-th plan of the file [default: every plan].")
@click.option("--functions", type=click.Path(dir_okay=False), metavar="FILE.py",
              help="Python file with user functions for (call ...).")
@click.option("-q", "--quiet", is_flag=True, help="Print only failures.")
def validate(domain, problem, plan_file, plan_index, functions, quiet):
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
    from htn.jshop.language.errors import HtnError
    from htn.jshop.language.functions import FunctionTable
    from htn.jshop.plans.planfile import read_plan_file
    from htn.jshop.plans.validate import check_steps, validate_plan
    from htn.jshop.readers.load import load_inputs

    table = FunctionTable()
    if functions:
        table.load_file(functions)
    dom, prob = load_inputs(domain, problem, table)
    pf = read_plan_file(plan_file)
    plans = pf.plans
    if plan_index is not None:
        if plan_index > len(plans):
            raise HtnError(f"--plan-index {plan_index}: the file holds {len(plans)} plan(s)",
                           plan_file)
        plans = [plans[plan_index - 1]]
    instance = prob.instances[0]
    for p in plans:
        check_steps(dom, p.steps, plan_file)
    bad = 0
    for p in plans:
        verdict = validate_plan(dom, instance, p, table)
        label = f"plan {p.index + 1}"
        if verdict.valid:
            if not quiet:
                click.echo(f"{label}: valid, {verdict.steps} steps, cost {p.cost:g}")
            continue
        bad += 1
        where = f"{plan_file}:{verdict.line}:1" if verdict.line else plan_file
        step = (f", step {verdict.failed_step + 1}" if verdict.failed_step is not None
                and verdict.failed_step < verdict.steps else "")
        click.echo(f"{where}: {label}{step}: {verdict.reason}", err=True)
    if len(plans) > 1 and not quiet:
        click.echo(f"{len(plans) - bad} of {len(plans)} plans valid")
    sys.exit(1 if bad else 0)
