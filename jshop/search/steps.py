"""What the search runs for each operator and method of the domain: the
entries of the planner's tables, built when a planner starts.

An operator's entry holds its head unifier, its precondition, the
substituter of its plan step and its cost; a method's its head unifier and,
per branch, its precondition, its body maker and whether the body is ordered
(manual 3.8, 5.2.2: a body is ordered unless written ``:unordered``, and
always in JSHOP2 1.0.3's mode, see :mod:`htn.jshop.search.planner`; an HDDL
body keeps its :class:`~htn.jshop.language.syntax.PartialOrder`). The
generated pieces are warming (:mod:`htn.jshop.logic.warming`): an entry is a
list, and a compiled piece replaces the interpreted one in place.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.logic import warming as warm
from htn.jshop.logic.codegen import where

from .network import compile_tasks


def operator_entry(logic, op: S.Operator) -> list:
    """``[operator, head unifier, precondition, head substituter, constant
    cost or None]``."""
    at = where(op.pos)
    entry = [
        op,
        None,
        logic.precondition(op.pre, op.head.args, f"precondition of {op.name}"),
        None,
        op.cost if type(op.cost) is float else None,
    ]
    entry[1] = warm.head_unifier(
        op.head.args,
        lambda: f"unifier of the head of {op.name}, {at}",
        lambda f: entry.__setitem__(1, f),
    )
    entry[3] = warm.substituter(
        op.head.args, lambda: f"plan step of {op.name}, {at}", lambda f: entry.__setitem__(3, f)
    )
    return entry


def method_entry(logic, m: S.Method, jshop2_compat: bool) -> list:
    """``[method, head unifier, [[precondition, body maker, ordered]] per branch]``."""
    at, pre = where(m.pos), logic.precondition
    branches = []
    for b in m.branches:
        branch = [
            pre(b.pre, m.head.args, f"precondition of {m.name} branch {b.label}"),
            None,
            jshop2_compat or b.tasks.order_flag,
        ]
        branch[1] = compile_tasks(
            b.tasks,
            f"subtasks of {m.name} branch {b.label}",
            lambda f, branch=branch: branch.__setitem__(1, f),
        )
        branches.append(branch)
    entry: list = [m, None, branches]
    entry[1] = warm.head_unifier(
        m.head.args,
        lambda: f"unifier of the head of {m.name}, {at}",
        lambda f: entry.__setitem__(1, f),
    )
    return entry
