"""Plan validation: replay a plan from the problem's initial state.

A plan is valid when its steps can be applied in sequence from the initial
state (manual 5.2.1): each step is an instance of an operator whose head
unifies with it and whose precondition has a satisfier in the state reached
so far; its effects (deletions, then additions) give the next state; no step
deletes a protected atom; and the plan's stated cost is the sum of its steps'
costs. When a precondition binds variables the step does not show (so
several satisfiers may give different effects or costs), every distinct
choice is tried, with backtracking, as the planner would have.

An HDDL problem's goal must also hold in the final state (HDDL, Höller et
al. 2020). A plan in this (JSHOP2) format has no decomposition, so any
applicable operator sequence with the right cost (and reaching the goal) is
valid; a plan in the IPC 2020 format (``htn plan -f ipc``) carries its
decomposition, which :mod:`htn.jshop.checks.ipc_verify` checks as well.
"""

from __future__ import annotations

from dataclasses import dataclass

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import atom_str, subst, term_str

from .unsatisfied import failing_literal
from .unsatisfied import show as _show


@dataclass
class Verdict:
    """The outcome of validating one plan."""

    valid: bool
    steps: int
    cost: float  # the steps' cost (of the deepest replay)
    failed_step: int | None = None  # 0-based index of the step that fails
    reason: str = ""
    line: int = 0  # the plan file's line of that step (or of its cost)


@dataclass
class Unpriced:
    """Steps to replay with :func:`validate_plan` whose cost is not stated
    (not checked)."""

    steps: list
    cost: None = None


def check_steps(domain: S.Domain, steps, file: str | None) -> None:
    """Every step must name an operator of the domain, with its arity."""
    for s in steps:
        ops = domain.operators.get(s.name)
        if not ops:
            raise HtnError(
                f"unknown operator {s.name}: the domain has no such operator",
                file,
                s.line or None,
                1 if s.line else None,
            )
        if all(len(o.head.args) != len(s.args) for o in ops):
            raise HtnError(
                f"{s.name} takes {len(ops[0].head.args)} argument(s), given {len(s.args)}",
                file,
                s.line or None,
                1 if s.line else None,
            )


def validate_plan(domain: S.Domain, instance: S.ProblemInstance, plan, functions=None) -> Verdict:
    """Replay ``plan`` (a :class:`~htn.jshop.plans.plan.Plan`) from ``instance``'s
    initial state; see the module docstring for what valid means."""
    from htn.jshop.search.planner import Planner

    planner = Planner.for_state(
        domain, instance.state, functions, goal=instance.goal, goal_nvars=instance.goal_nvars
    )
    steps = plan.steps
    n = len(steps)
    changes: list = []  # applied change of each step so far
    costs: list = []
    frames = [_options(planner, steps[0])] if n else []
    deepest = Verdict(False, n, 0.0)
    while True:
        k = len(changes)
        if k == n:
            total = sum(costs)
            cost_ok = plan.cost is None or abs(total - plan.cost) <= 1e-9 * max(1.0, abs(total))
            goal_ok = instance.goal is None or planner.goal_holds()
            if cost_ok and goal_ok:
                return Verdict(True, n, total)
            if not goal_ok:
                if deepest.failed_step is None or deepest.failed_step < n:
                    deepest = Verdict(
                        False, n, total, n, why_goal(planner, instance), getattr(plan, "line", 0)
                    )
            elif deepest.failed_step is None:
                deepest = Verdict(
                    False,
                    n,
                    total,
                    n,
                    f"the plan's cost is "
                    f"{term_str(float(plan.cost))} but its steps cost "
                    f"{term_str(float(total))}",
                    getattr(plan, "line", 0),
                )
            if not _undo_last(planner, changes, costs):  # try the last step's next choice
                return deepest
            continue
        option = next(frames[-1], None)
        if option is None:
            if deepest.failed_step is None or k > deepest.failed_step:
                deepest = Verdict(
                    False, n, sum(costs), k, why_step(planner, steps[k]), steps[k].line
                )
            frames.pop()
            if not frames or not _undo_last(planner, changes, costs):
                return deepest
            continue
        op, env, cost = option
        change = planner.apply(op, env)
        if change is None:
            if deepest.failed_step is None or k > deepest.failed_step:
                deepest = Verdict(
                    False,
                    n,
                    sum(costs),
                    k,
                    f"{steps[k]} would delete a protected atom",
                    steps[k].line,
                )
            continue
        changes.append(change)
        costs.append(cost)
        if k + 1 < n:
            frames.append(_options(planner, steps[k + 1]))


def _undo_last(planner, changes, costs) -> bool:
    if not changes:
        return False
    changes.pop().undo(planner.state)
    costs.pop()
    return True


def _options(planner, step):
    """The distinct ways to apply ``step``: (operator, binding, cost), one per
    distinct (operator, effects, cost)."""
    seen = set()
    for op, env in planner.step_options(step.name, step.args):
        cost = subst(op.cost, env)
        if type(cost) is not float:
            continue
        dels, adds = planner.effects(op, env)
        key = (id(op), tuple(dels), tuple(adds), cost)
        if key in seen:
            continue
        seen.add(key)
        yield op, env, cost


def why_step(planner, step) -> str:
    """Why no operator applies to ``step``: the first literal of a
    precondition that has no satisfier, under the step's bindings."""
    from htn.jshop.logic.compile import head_unifier

    reasons = []
    for op in planner.domain.operators.get(step.name, ()):
        env = [None] * op.nvars
        if not head_unifier(op.head.args)(tuple(step.args), env):
            reasons.append(f"{step} does not match {atom_str(op.name, op.head.args)}")
            continue
        item, bound = failing_literal(planner.logic, op.pre.expr, env)
        if item is None:
            reasons.append(f"precondition of {step} does not hold")
        else:
            reasons.append(
                f"precondition of {step} does not hold: {_show(item, bound)} has no satisfier"
            )
    return "; ".join(reasons) or f"no operator applies to {step}"


def why_goal(planner, instance) -> str:
    """The first conjunct of the goal that does not hold in the final state."""
    env = [None] * instance.goal_nvars
    item, bound = failing_literal(planner.logic, instance.goal.expr, env)
    if item is not None:
        return f"the goal does not hold in the final state: {_show(item, bound)} is false"
    return "the goal does not hold in the final state"
