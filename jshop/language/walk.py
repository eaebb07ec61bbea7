"""Walkers over the variables of terms, expressions, preconditions, task lists
and effects: ``cb(var)`` for every :class:`~htn.jshop.language.terms.Var` in
textual order. The readers number variables with them (manual 5.1.1); the
checks, the compiled conjunctions and the HDDL builder collect variables."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from . import syntax as S
from .terms import variables

if TYPE_CHECKING:
    from collections.abc import Callable

    from .terms import Var

    _Visit = Callable[[Var], object]  # called for every variable met


def walk_term(t: Any, cb: _Visit) -> None:
    for v in variables(t, []):
        cb(v)


def walk_expr(e: Any, cb: _Visit) -> None:
    if isinstance(e, S.Atom):
        walk_term(e.args, cb)
    elif isinstance(e, S.VarAtom):
        cb(e.var)
    elif isinstance(e, (S.And, S.Or)):
        for x in e.items:
            walk_expr(x, cb)
    elif isinstance(e, S.Not):
        walk_expr(e.expr, cb)
    elif isinstance(e, S.ForAll):
        walk_expr(e.cond, cb)
        walk_expr(e.then, cb)
        for v in e.vars:
            cb(v)
    elif isinstance(e, S.Assign):
        walk_term(e.term, cb)
        cb(e.var)
    elif isinstance(e, S.CallExpr):
        walk_term(e.call, cb)
    elif isinstance(e, S.Equal):  # HDDL's (= a b)
        walk_term((e.left, e.right), cb)


def walk_pre(p: S.Precondition, cb: _Visit) -> None:
    if p.sort_var is not None:
        cb(p.sort_var)
    walk_expr(p.expr, cb)


def walk_tasks(tl: S.TaskList | S.TaskAtom, cb: _Visit) -> None:
    if isinstance(tl, S.TaskAtom):
        walk_term(tl.args, cb)
    else:
        for x in tl.items:
            walk_tasks(x, cb)


def walk_effects(eff: S.Effects, cb: _Visit) -> None:
    if eff.var is not None:
        cb(eff.var)
    for x in eff.items:
        if isinstance(x, S.Protection):
            walk_expr(x.atom, cb)
        elif isinstance(x, S.EffectForAll):
            walk_expr(x.cond, cb)
            for a in x.atoms:
                walk_expr(a, cb)
            for v in x.vars:
                cb(v)
        else:
            walk_expr(x, cb)
