"""Variables numbered per domain element, in the order JSHOP2's parser meets
them (manual 5.1.1): that index is a variable's slot in a binding, and what
an unbound variable prints as (``VAR<n>``)."""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var
from htn.jshop.language.walk import walk_effects, walk_pre, walk_tasks, walk_term

# JSHOP2 adds a variable to its element's list when its parser first reads it:
# textual order, except that (assign ?v t) reads t before adding ?v. A variable
# that is only ever used as an atom or as a delete/add list is looked up, not
# added; we add it so that such domains get a checkable error instead of -1.


def index_var(scope: dict, v: Var) -> None:
    if v.name not in scope:
        scope[v.name] = len(scope)
    v.index = scope[v.name]


def number_operator(op: S.Operator) -> int:
    scope: dict = {}
    cb = lambda v: index_var(scope, v)  # noqa: E731
    walk_term(op.head.args, cb)
    walk_pre(op.pre, cb)
    walk_effects(op.delete, cb)
    walk_effects(op.add, cb)
    walk_term(op.cost, cb)
    return len(scope)


def number_method(m: S.Method) -> int:
    scope: dict = {}
    cb = lambda v: index_var(scope, v)  # noqa: E731
    walk_term(m.head.args, cb)
    for b in m.branches:
        walk_pre(b.pre, cb)
        walk_tasks(b.tasks, cb)
    return len(scope)


def number_axiom(ax: S.Axiom) -> int:
    scope: dict = {}
    cb = lambda v: index_var(scope, v)  # noqa: E731
    walk_term(ax.head.args, cb)
    for b in ax.branches:
        walk_pre(b.pre, cb)
    return len(scope)
