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
al. 2020). Validation does not check that the plan is a decomposition of the
problem's tasks: any applicable operator sequence with the right cost (and
reaching the goal) is valid; for HDDL, the IPC 2020 verifier checks the
decomposition that ``htn plan -f ipc`` prints.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

from . import syntax as S
from .errors import HtnError
from .terms import Var, atom_str, subst, term_str


@dataclass
class Verdict:
    """The outcome of validating one plan."""
    valid: bool
    steps: int
    cost: float                  # the steps' cost (of the deepest replay)
    failed_step: Optional[int] = None    # 0-based index of the step that fails
    reason: str = ""
    line: int = 0                # the plan file's line of that step (or of its cost)


def check_steps(domain: S.Domain, steps, file: str) -> None:
    """Every step must name an operator of the domain, with its arity."""
    for s in steps:
        ops = domain.operators.get(s.name)
        if not ops:
            raise HtnError(f"unknown operator {s.name}: the domain has no such operator",
                           file, s.line or None, 1 if s.line else None)
        if all(len(o.head.args) != len(s.args) for o in ops):
            raise HtnError(f"{s.name} takes {len(ops[0].head.args)} argument(s), given "
                           f"{len(s.args)}", file, s.line or None, 1 if s.line else None)


def validate_plan(domain: S.Domain, instance: S.ProblemInstance, plan,
                  functions=None) -> Verdict:
    """Replay ``plan`` (a :class:`~htn.jshop.plan.Plan`) from ``instance``'s
    initial state; see the module docstring for what valid means."""
    from .planner import Planner
    planner = Planner(domain, S.ProblemInstance(instance.state, S.TaskList([]),
                                                goal=instance.goal,
                                                goal_nvars=instance.goal_nvars),
                      functions, loop_check=False)
    steps = plan.steps
    n = len(steps)
    changes: list = []            # applied change of each step so far
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
                    deepest = Verdict(False, n, total, n, _why_goal(planner, instance),
                                      getattr(plan, "line", 0))
            elif deepest.failed_step is None:
                deepest = Verdict(False, n, total, n, f"the plan's cost is "
                                  f"{term_str(float(plan.cost))} but its steps cost "
                                  f"{term_str(float(total))}", getattr(plan, "line", 0))
            if not _undo_last(planner, changes, costs):   # try the last step's next choice
                return deepest
            continue
        option = next(frames[-1], None)
        if option is None:
            if deepest.failed_step is None or k > deepest.failed_step:
                deepest = Verdict(False, n, sum(costs), k, _why(planner, steps[k]),
                                  steps[k].line)
            frames.pop()
            if not frames or not _undo_last(planner, changes, costs):
                return deepest
            continue
        op, env, cost = option
        change = planner.apply(op, env)
        if change is None:
            if deepest.failed_step is None or k > deepest.failed_step:
                deepest = Verdict(False, n, sum(costs), k,
                                  f"{steps[k]} would delete a protected atom", steps[k].line)
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


def _why(planner, step) -> str:
    """Why no operator applies to ``step``: the first literal of a
    precondition that has no satisfier, under the step's bindings."""
    from .compile import head_unifier
    reasons = []
    for op in planner.domain.operators.get(step.name, ()):
        env = [None] * op.nvars
        if not head_unifier(op.head.args)(tuple(step.args), env):
            reasons.append(f"{step} does not match {atom_str(op.name, op.head.args)}")
            continue
        expr = op.pre.expr
        items = expr.items if isinstance(expr, S.And) else [expr]
        for j in range(1, len(items) + 1):
            sat = planner.logic.expr(S.And(items[:j]) if j > 1 else items[0])
            if next(iter(sat(env)), None) is None:
                reasons.append(f"precondition of {step} does not hold: "
                               f"{_show(items[j - 1], env)} has no satisfier")
                break
        else:
            reasons.append(f"precondition of {step} does not hold")
    return "; ".join(reasons) or f"no operator applies to {step}"


def _why_goal(planner, instance) -> str:
    """The first conjunct of the goal that does not hold in the final state."""
    expr = instance.goal.expr
    items = expr.items if isinstance(expr, S.And) else [expr]
    env = [None] * instance.goal_nvars
    for item in items:
        if next(iter(planner.logic.expr(item)(env)), None) is None:
            return f"the goal does not hold in the final state: {_show(item, env)} is false"
    return "the goal does not hold in the final state"


def _show(e, env) -> str:
    """An expression in source form, variables replaced by their bindings."""
    from .functions import STDLIB_JAVA_NAMES
    from .terms import CallTerm
    written = {java: name for name, java in STDLIB_JAVA_NAMES.items()}

    def term(t):
        if type(t) is CallTerm:
            name = written.get(t.name, t.name)
            return "(call " + " ".join([name, *[term(a) for a in t.args]]) + ")"
        t = subst(t, env) if type(t) is not CallTerm else t
        if type(t) is Var:
            return t.name
        if type(t) is tuple:
            return "(" + " ".join(term(x) for x in t) + ")" if t else "nil"
        return term_str(t)
    if isinstance(e, S.Atom):
        return "(" + " ".join([e.pred, *[term(a) for a in e.args]]) + ")"
    if isinstance(e, S.Not):
        return f"(not {_show(e.expr, env)})"
    if isinstance(e, (S.And, S.Or)):
        word = "and" if isinstance(e, S.And) else "or"
        return f"({word} " + " ".join(_show(x, env) for x in e.items) + ")"
    if isinstance(e, S.CallExpr):
        return term(e.call)
    if isinstance(e, S.Equal):
        return f"(= {term(e.left)} {term(e.right)})"
    if isinstance(e, S.ForAll):
        names = " ".join(v.name for v in e.vars)
        return f"(forall ({names}) {_show(e.cond, env)} {_show(e.then, env)})"
    if isinstance(e, S.Assign):
        return f"(assign {e.var.name} {term(e.term)})"
    pos = getattr(e, "pos", None)
    return f"the {type(e).__name__.lower()} expression" + (f" at {pos}" if pos else "")
