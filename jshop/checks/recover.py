"""The task tree behind a plan that lacks one, and checks before a plan runs.

``htn plan -o`` writes each plan's task tree into the plan file
(:mod:`htn.jshop.plans.planfile`), and ``htn run`` executes that tree. A plan
file without one (hand-written, from JSHOP2, or from an htn before task trees
were written) gets its tree (which the behaviour tree mirrors, and which
repair re-plans in) by planning the problem again with trees recorded and
taking the first plan whose steps are the file's: ``htn plan`` writes the
planner's plans in that order. An older transformed plan's file notes its
task list (``; tasks:``), which is planned instead. A plan no decomposition
gives (a hand-written one) has no recoverable tree; it runs as one sequence.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import Var
from htn.jshop.search.planner import Planner

RECOVER_TIMEOUT = 5.0  # seconds of search
RECOVER_PLANS = 50  # plans looked at, at most


def recover_tree(
    domain: S.Domain,
    instance: S.ProblemInstance,
    steps,
    functions=None,
    timeout: float = RECOVER_TIMEOUT,
    max_plans: int = RECOVER_PLANS,
    tasks: str | None = None,
):
    """The task tree of the first plan of ``instance`` whose steps are ``steps``,
    or None. ``tasks`` (a task list's text, as ``htn transform -o`` notes it)
    replaces the problem's task list."""
    if tasks:
        from htn.jshop.readers.load import parse_text

        try:
            listed = (
                parse_text(f"(defproblem tasks {domain.name} () ({tasks}))", "<tasks>")
                .instances[0]
                .tasks
            )
        except HtnError:
            return None
        instance = S.ProblemInstance(instance.state, listed, instance.pos)
    want = [str(s) for s in steps]
    plans = Planner(domain, instance, functions, record_trees=True).plans(timeout=timeout)
    for k, plan in enumerate(plans):
        assert plan is not None  # no slices of CPU time are asked for
        if plan.lines() == want:
            return plan.tree
        if k + 1 >= max_plans:
            break
    return None


def _variable(term) -> Var | None:
    stack = [term]
    while stack:
        t = stack.pop()
        if isinstance(t, Var):
            return t
        if isinstance(t, (list, tuple)):
            stack.extend(t)
    return None


def check_runnable(
    domain: S.Domain,
    instance: S.ProblemInstance,
    plan,
    plan_file: str | None,
    functions=None,
    lines=(),
) -> None:
    """Before the robot moves: every step is ground, and the steps apply in
    sequence from the problem's initial state (manual 5.2.1; the plan's cost
    is not checked). A bad step is an input error at its line of the plan
    file (``lines``: the file's text, which locates a variable's column)."""
    from htn.jshop.checks.validate import Unpriced, validate_plan

    for s in plan.steps:
        var = next((v for v in map(_variable, s.args) if v is not None), None)
        if var is not None:
            text = lines[s.line - 1] if 0 < s.line <= len(lines) else ""
            col = text.find(var.name) + 1 if var.name in text else 1
            shown = text.strip() or s.name
            raise HtnError(
                f"{shown} has a variable, {var.name}: a plan to run must be ground",
                plan_file,
                s.line or None,
                col if s.line else None,
            )
    verdict = validate_plan(domain, instance, Unpriced(plan.steps), functions)
    if not verdict.valid:
        assert verdict.failed_step is not None  # set in every invalid verdict
        where = verdict.line or None
        raise HtnError(
            f"step {verdict.failed_step + 1} cannot run: {verdict.reason}",
            plan_file,
            where,
            1 if where else None,
        )
