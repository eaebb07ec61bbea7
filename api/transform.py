"""The transform use case: plan a problem, transform its task tree with the
registered rules and check the result (``htn transform``; the
plan-transformations paper, Table I: :mod:`htn.transform.framework`).

Every transformed plan is planned again from the rewritten task list, so each
step's precondition holds in sequence from the initial state; a rewrite that
breaks the plan, or costs more on the chosen metric, is rolled back.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from htn.files import atomic_write
from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import Guard
from htn.jshop.language.terms import source_atom
from htn.jshop.plans.plan import Plan
from htn.jshop.plans.planfile import header, plan_text

from .inputs import function_table, path_of, read_inputs

if TYPE_CHECKING:
    from htn.transform.framework import Workspace

    from .inputs import DomainInput, FunctionsInput, ProblemInput, StrPath

# the rules to apply: names, or one comma-separated text (None: every enabled one)
Rules = str | Collection[str] | None


class UnknownRules(HtnError):
    """``rules`` names a transformation that is not registered."""

    def __init__(self, unknown: list[str], known: list[str]):
        super().__init__(f"unknown rule(s) {', '.join(unknown)}; known: {', '.join(known)}")
        self.unknown, self.known = unknown, known


@dataclass
class TransformResult:
    """What a transformation did: ``document`` (the ``htn transform --json``
    object: rules applied and why others were not, the changes, the
    original's and the transformed plan's length and cost on the metric, the
    annotated tree), the transformed ``plan`` (with its task ``tree``) and
    the rewritten top-level ``tasks``."""

    document: dict[str, Any]
    plan: Plan
    tasks: list[str]
    workspace: Workspace

    def plan_file_text(
        self, out_path: str, domain: str | None = None, problem: str | None = None
    ) -> str:
        """The transformed plan as a plan file at ``out_path`` (for
        :func:`htn.run` and ``htn run``): the header naming ``domain`` and
        ``problem``, the rewritten task list (``; tasks:``), the plan's task
        tree and the plan (:mod:`htn.jshop.plans.planfile`)."""
        ws = self.workspace
        domain = domain or path_of(ws.domain)
        problem = problem or self.document["problem"]
        return (
            header(out_path, domain, problem)
            + f"; tasks: {' '.join(self.tasks)}\n"
            + plan_text(self.plan)
        )


def transform_plan(
    domain: DomainInput,
    problem: ProblemInput,
    *,
    rules: Rules = None,
    metric: str = "navigation",
    functions: FunctionsInput = None,
    on_warning: Callable[[str], None] | None = None,
    on_phase: Callable[[str], None] | None = None,
    stops: Guard | None = None,
    output: StrPath | None = None,
) -> TransformResult:
    """Plan ``problem`` (its first instance), apply the registered
    transformations in priority order (tray > container > both-hands, and any
    plugins'), or only ``rules`` (names, or one comma-separated text), and
    keep each rewrite that keeps the plan valid and does not cost more on
    ``metric`` (``navigation``, ``manipulation``, ``actions``: means over
    projected runs; ``navigation-static``: distances between area centres).

    ``on_warning`` gets each located warning of the inputs' check (as
    :func:`htn.plan` has them), before planning; ``on_phase`` a few words
    as each phase begins (planning, each rule's projections), for progress.
    ``stops``: the command's :class:`htn.process.Stops` (user functions run
    under them). ``output``: a plan file for the transformed plan (the
    rewritten task list, its tree: ``htn run`` executes it), checked before
    any work and replaced only once all is done."""
    if output is None:
        return _transform(domain, problem, rules, metric, functions, on_warning, on_phase, stops)
    output = str(output)
    with atomic_write(output, "-o", (path_of(domain), path_of(problem))) as out:
        done = _transform(domain, problem, rules, metric, functions, on_warning, on_phase, stops)
        out.write(done.plan_file_text(output, path_of(domain), path_of(problem)))
    return done


def _transform(
    domain: DomainInput,
    problem: ProblemInput,
    rules: Rules,
    metric: str,
    functions: FunctionsInput,
    on_warning: Callable[[str], None] | None,
    on_phase: Callable[[str], None] | None,
    stops: Guard | None,
) -> TransformResult:
    from htn.transform.framework import METRICS, Workspace
    from htn.transform.registered import default_framework

    if metric not in METRICS:
        raise HtnError(f"unknown metric {metric}; known: {', '.join(METRICS)}")
    fw = default_framework()
    names = [t.name for t in fw.transformations]
    if isinstance(rules, str):
        rules = [r.strip() for r in rules.split(",") if r.strip()]
    if rules:
        unknown = [r for r in rules if r not in names]
        if unknown:
            raise UnknownRules(unknown, names)
    say = on_phase or (lambda text: None)
    inputs = read_inputs(domain, problem, function_table(functions, stops))
    dom, prob = inputs.domain, inputs.problem
    if on_warning:
        for w in inputs.warnings:
            on_warning(w)
    say("planning")
    ws = Workspace.from_problem(dom, prob.instances[0])
    original = ws.plan
    assert isinstance(original, Plan)  # the problem's first plan (from_problem)
    enabled = {t.name: t.enabled for t in fw.transformations}
    try:
        if rules:
            for t in fw.transformations:
                t.enabled = t.name in rules
        fw.apply_all_transformations(ws, metric, on_phase=say)
    finally:  # the registered framework is shared: leave it as it was
        for t in fw.transformations:
            t.enabled = enabled[t.name]
    cost = METRICS[metric]
    plan = ws.plan
    assert isinstance(plan, Plan)  # the original, or the last transformed plan kept
    changes = [
        {
            "rule": u.transformed_by,
            "paths": u.paths,
            "tasks": [source_atom(t.name, t.args) for t in u.tasks],
        }
        for u in ws.units
        if u.transformed_by
    ]
    document: dict[str, Any] = {
        "problem": path_of(problem) or path_of(prob),
        "metric": metric,
        "applied": [r for r, status, _ in ws.log if status == "applied"],
        "log": [{"rule": r, "status": s, "detail": d} for r, s, d in ws.log],
        "changes": changes,
        "original": {"steps": len(original.steps), metric: cost(ws, original)},
        "transformed": {
            "steps": len(plan.steps),
            metric: cost(ws, plan),
            "plan": plan.lines(),
        },
        "tree": ws.annotated_tree().to_dict(),
    }
    tasks = [source_atom(t.name, t.args) for t in S.task_atoms(ws.task_list())]
    return TransformResult(document, plan, tasks, ws)
