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
    from htn.jshop.language.errors import HtnError
    from htn.jshop.language.functions import FunctionTable
    from htn.jshop.plans.planfile import read_plan_file
    from htn.jshop.plans.validate import check_steps, validate_plan
    from htn.jshop.readers.load import load_inputs

    table = FunctionTable()
    if functions:
        table.load_file(functions)
    dom, prob = load_inputs(domain, problem, table)
    ipc = _ipc_text(plan_file)
    if ipc is not None:
        sys.exit(_validate_ipc(dom, prob, plan_file, ipc, plan_index, table, quiet))
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


def _ipc_text(path: str):
    """The plan file's text if it holds IPC plans, else None."""
    import os

    from htn.jshop.plans.ipc import is_ipc_text
    from htn.jshop.readers.source import read_source
    if not os.path.isfile(path):
        return None
    text = read_source(path)
    return text if is_ipc_text(text) else None


def _validate_ipc(dom, prob, plan_file, text, plan_index, table, quiet) -> int:
    from htn.jshop.plans.ipc_verify import verify_ipc_text
    results = verify_ipc_text(dom, prob, text, plan_file, plan_index, table)
    bad = 0
    for p, verdict in results:
        label = f"plan {p.index + 1}"
        if verdict.valid:
            if not quiet:
                click.echo(f"{label}: valid, {verdict.actions} actions, "
                           f"{verdict.decompositions} decompositions")
            continue
        bad += 1
        for f in verdict.findings[:10]:
            click.echo(f"{plan_file}:{f.line}:{f.col}: {label}: {f.message}", err=True)
        if len(verdict.findings) > 10:
            click.echo(f"{plan_file}: {label}: ... and {len(verdict.findings) - 10} more",
                       err=True)
    if len(results) > 1 and not quiet:
        click.echo(f"{len(results) - bad} of {len(results)} plans valid")
    return 1 if bad else 0
