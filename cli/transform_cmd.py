"""``htn transform DOMAIN PROBLEM``: apply plan transformations to a plan's task tree."""
from __future__ import annotations

import contextlib
import json
import sys

import click

from .output import atomic_write


@click.command("transform")
@click.argument("domain", type=click.Path(dir_okay=False))
@click.argument("problem", type=click.Path(dir_okay=False))
@click.option("--rules", metavar="NAME,...",
              help="Only these transformations (default: all registered: tray, container, "
                   "both-hands).")
@click.option("--metric", type=click.Choice(["navigation", "manipulation", "actions",
                                              "navigation-static"]),
              default="navigation", show_default=True,
              help="A transformation that makes this worse (mean over 64 projected runs; "
                   "navigation-static: distance between area centres) is rolled back.")
@click.option("-o", "--output", type=click.Path(dir_okay=False),
              help="Write the transformed plan (jshop format with header) for 'htn run'.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
def transform(domain, problem, rules, metric, output, as_json):
    """Plan PROBLEM, transform its task tree with the registered rules
    (tray > container > both-hands), check and print what changed.

    \b
    Every transformed plan is re-planned from the rewritten task list, so each
    step's precondition holds in sequence from the initial state; a rewrite
    that breaks the plan or costs more on --metric is rolled back.
    """
    from htn.jshop.language import syntax as S
    from htn.jshop.plans.planfile import header

    # a bad -o fails before the work; the file is replaced once all is done
    with atomic_write(output, "-o") if output else contextlib.nullcontext() as out:
        result, ws = _transform(domain, problem, rules, metric)
        if out:
            out.write(header(output, domain, problem))
            # the rewritten task list: htn run recovers the plan's task tree from it
            out.write(f"; tasks: {' '.join(_task_text(t) for t in S.task_atoms(ws.task_list()))}\n")
            out.write(ws.plan.to_jshop())
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
    click.echo(f"\nplan: {o['steps']} -> {t['steps']} steps; {metric}: "
               f"{o[metric]:.2f} -> {t[metric]:.2f}")
    sys.stdout.flush()


def _transform(domain: str, problem: str, rules, metric: str):
    """Plan, transform and check; the result document and the workspace."""
    from htn.jshop.readers.load import load_inputs
    from htn.transform.framework import METRICS, Workspace
    from htn.transform.registered import default_framework

    fw = default_framework()
    names = [t.name for t in fw.transformations]
    if rules:
        wanted = [r.strip() for r in rules.split(",") if r.strip()]
        unknown = [r for r in wanted if r not in names]
        if unknown:
            raise click.BadParameter(f"unknown rule(s) {', '.join(unknown)}; "
                                     f"known: {', '.join(names)}", param_hint="--rules")
        for t in fw.transformations:
            t.enabled = t.name in wanted
    dom, prob = load_inputs(domain, problem)
    ws = Workspace.from_problem(dom, prob.instances[0])
    original = ws.plan
    fw.apply_all_transformations(ws, metric)
    cost = METRICS[metric]
    changes = [{"rule": u.transformed_by, "paths": u.paths,
                "tasks": [str(_task_text(t)) for t in u.tasks]}
               for u in ws.units if u.transformed_by]
    result = {
        "problem": problem, "metric": metric,
        "applied": [r for r, status, _ in ws.log if status == "applied"],
        "log": [{"rule": r, "status": s, "detail": d} for r, s, d in ws.log],
        "changes": changes,
        "original": {"steps": len(original.steps), metric: cost(ws, original)},
        "transformed": {"steps": len(ws.plan.steps), metric: cost(ws, ws.plan),
                        "plan": ws.plan.lines()},
        "tree": ws.annotated_tree().to_dict(),
    }
    return result, ws


def _task_text(t) -> str:
    from htn.jshop.language.terms import source_atom
    return source_atom(t.name, t.args)
