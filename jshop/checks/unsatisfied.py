"""Which literal of a precondition fails, shown as the source wrote it.

``--explain`` (:mod:`htn.jshop.checks.explain`) and ``htn validate``
(:mod:`htn.jshop.checks.validate`) both answer "why does this precondition not hold
here": the first conjunct, in evaluation order (manual 4.2: left to right),
that has no satisfier under the bindings found for the conjuncts before it.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var, subst, term_str


def failing_literal(logic, expr, env: list, cache: dict | None = None):
    """The first conjunct of ``expr`` with no satisfier after those before
    it, and the bindings under which it failed; ``(None, env)`` when the
    whole expression holds. ``logic`` is the planner's
    :class:`~htn.jshop.logic.engine.Logic`; ``cache`` keeps the compiled prefixes
    of expressions asked about again (keyed by the expression's identity)."""
    items = expr.items if isinstance(expr, S.And) else [expr]
    cache = {} if cache is None else cache
    bound = env
    for j in range(len(items)):
        key = (id(expr), j)
        sat = cache.get(key)
        if sat is None:
            sat = cache[key] = logic.expr(S.And(list(items[: j + 1])) if j else items[0])
        found = next(iter(sat(env)), None)
        if found is None:
            return items[j], bound
        bound = found
    return None, env


def show(e, env) -> str:
    """An expression in source form, variables replaced by their bindings."""
    from htn.jshop.language.functions import STDLIB_JAVA_NAMES
    from htn.jshop.language.terms import CallTerm

    written = {java: name for name, java in STDLIB_JAVA_NAMES.items()}

    def term(t):
        if type(t) is CallTerm:
            name = written.get(t.name, t.name)
            return "(call " + " ".join([name, *[term(a) for a in t.args]]) + ")"
        t = subst(t, env)
        if type(t) is Var:
            return t.name
        if type(t) is tuple:
            return "(" + " ".join(term(x) for x in t) + ")" if t else "nil"
        return term_str(t)

    if isinstance(e, S.Atom):
        return "(" + " ".join([e.pred, *[term(a) for a in e.args]]) + ")"
    if isinstance(e, S.Not):
        return f"(not {show(e.expr, env)})"
    if isinstance(e, (S.And, S.Or)):
        word = "and" if isinstance(e, S.And) else "or"
        return f"({word} " + " ".join(show(x, env) for x in e.items) + ")"
    if isinstance(e, S.CallExpr):
        return term(e.call)
    if isinstance(e, S.Equal):
        return f"(= {term(e.left)} {term(e.right)})"
    if isinstance(e, S.ForAll):
        names = " ".join(v.name for v in e.vars)
        return f"(forall ({names}) {show(e.cond, env)} {show(e.then, env)})"
    if isinstance(e, S.Assign):
        return f"(assign {e.var.name} {term(e.term)})"
    pos = getattr(e, "pos", None)
    return f"the {type(e).__name__.lower()} expression" + (f" at {pos}" if pos else "")
