"""Goal guard: cut a branch once the problem's goal can no longer hold (HDDL).

An HDDL problem may have a goal that the plan's final state must satisfy
(Höller et al., AAAI 2020). Depth-first decomposition only finds out at the
end of a plan, and a domain like Blocksworld-GTOHP offers at each tower two
ways to go on, of which one undoes an earlier goal atom: the plan would be
found only after trying 2^15 complete plans.

The guard checks, whenever an action deletes an atom that the goal needs (or
adds one that the goal forbids), whether some task still in the network could
add it back (delete it again). What a task can add or delete is summarised
per task name, as patterns over its arguments: an action's effects, and for a
compound task the union over its methods of its subtasks' patterns, with a
method's own variables as wildcards (a fixpoint for recursive tasks). The
summary over-approximates, so the cut is sound: no plan is lost. Only the
goal's top-level literals are guarded.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

ANY = object()  # a wildcard argument in a pattern


class GoalGuard:
    """Which goal literals an action broke, and whether they can be mended."""

    def __init__(self, domain: S.Domain, goal: S.Precondition):
        self.needed, self.forbidden = set(), set()
        expr = goal.expr
        for item in expr.items if isinstance(expr, S.And) else [expr]:
            if isinstance(item, S.Atom) and not any(type(a) is Var for a in item.args):
                self.needed.add((item.pred, item.args))
            elif (
                isinstance(item, S.Not)
                and isinstance(item.expr, S.Atom)
                and not any(type(a) is Var for a in item.expr.args)
            ):
                self.forbidden.add((item.expr.pred, item.expr.args))
        self.adds, self.dels = _summaries(domain)

    def __bool__(self) -> bool:
        return bool(self.needed or self.forbidden)

    def broken(self, change, state, root, cursor=None) -> bool:
        """After an action: True if it broke a goal literal that no task
        left in the network (below ``root``) can mend. ``cursor``, the
        planner's path to the action (see ``Planner._first``), lets the
        nearest tasks be looked at first."""
        for pred, args, _i in change.deleted:
            if (
                (pred, args) in self.needed
                and not state.has(pred, args)
                and not self._mendable(root, cursor, self.adds, pred, args)
            ):
                return True
        for pred, args in change.added:
            if (
                (pred, args) in self.forbidden
                and state.has(pred, args)
                and not self._mendable(root, cursor, self.dels, pred, args)
            ):
                return True
        return False

    def _mendable(self, root, cursor, table: dict, pred: str, args: tuple) -> bool:
        tasks = _after(cursor) if cursor else _pending_tasks(root)
        for task in tasks:
            for ppred, pargs in table.get(task.name, ()):
                if ppred == pred and _matches(pargs, task.args, args):
                    return True
        return False


def _matches(pattern: tuple, task_args: tuple, args: tuple) -> bool:
    if len(pattern) != len(args):
        return False
    for p, a in zip(pattern, args):
        if p is ANY:
            continue
        if type(p) is int:
            p = task_args[p]
            if type(p) is Var:
                continue
        if p != a:
            return False
    return True


def _after(cursor: list):
    """The tasks left after the one at the end of ``cursor``, nearest first:
    in an ordered network, those of the later members of each ancestor."""
    for node, i in reversed(cursor):
        for sibling in node.subtasks[i + 1 :]:
            yield from _pending_tasks(sibling)


def _pending_tasks(root):
    """The tasks of the network not reduced or applied yet."""
    stack = [root]
    while stack:
        node = stack.pop()
        subs = node.subtasks
        if subs is None:
            if node.task is not None:
                yield node.task
            continue
        if node.done:
            continue
        stack.extend(reversed(subs[node.start :]))


def _summaries(domain: S.Domain) -> tuple[dict, dict]:
    """task name -> {(pred, pattern)} it may add, and the same for deletes."""
    adds: dict = {}
    dels: dict = {}
    for name, ops in domain.operators.items():
        for op in ops:
            slots = {a.index: i for i, a in enumerate(op.head.args) if type(a) is Var}
            adds.setdefault(name, set()).update(_effect_patterns(op.add, slots))
            dels.setdefault(name, set()).update(_effect_patterns(op.delete, slots))
    for table in (adds, dels):
        changed = True
        while changed:
            changed = False
            for name, methods in domain.methods.items():
                mine = table.setdefault(name, set())
                before = len(mine)
                for m in methods:
                    slots = {a.index: i for i, a in enumerate(m.head.args) if type(a) is Var}
                    for b in m.branches:
                        for t in S.task_atoms(b.tasks):
                            for pred, pattern in list(table.get(t.name, ())):
                                mine.add((pred, tuple(_lift(p, t.args, slots) for p in pattern)))
                changed |= len(mine) != before
    return adds, dels


def _effect_patterns(eff: S.Effects, slots: dict):
    if eff.var is not None:
        return
    for item in eff.items:
        atoms = item.atoms if isinstance(item, S.EffectForAll) else [item]
        for a in atoms:
            if isinstance(a, S.Atom):
                yield a.pred, tuple(_position(x, slots) for x in a.args)


def _position(x, slots: dict):
    if type(x) is Var:
        return slots.get(x.index, ANY)
    return x if type(x) in (str, float) else ANY


def _lift(p, call_args: tuple, slots: dict):
    """A callee's pattern element in the caller's terms."""
    if p is ANY or type(p) is not int:
        return p
    return _position(call_args[p], slots)
