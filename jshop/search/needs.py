"""Needs guard: cut a branch once a task still to do needs an atom that is gone for good.

Some atoms are only ever deleted: no action adds an atom of their predicate
(Factories' ``location-free``: building a factory takes the place for good).
Once such an atom is false it stays false, so a task still in the network
whose every way of being done needs it can never be done. Depth-first search
would only find out when it reaches that task, which in Factories-simple is
the last step of a plan thousands of actions long (the final factory needs
its place still free): every factory built on that place earlier is a dead
end that chronological backtracking takes exponential time to leave.

The guard runs after an action that deleted such an atom, and asks whether
some task left in the network needs it. What a task needs is summarised per
task name as patterns over its arguments: the positive atoms of those
predicates in the top-level conjunction of an action's precondition, and for
a compound task the atoms that all of its methods need (a method needs its
own precondition's atoms and what its subtasks need). Only atoms fixed by the
task's arguments and constants count, so the cut is sound: a task that is
cut really has no way left of being done, and no plan is lost.

Read for HDDL domains (the planner's ``loop_check`` setting); the summary
is empty, and the guard off, when the domain has no such predicate.
"""

from __future__ import annotations

from collections.abc import Container

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

from .goals import _after, _pending_tasks


class NeedGuard:
    """Which atoms of only-deleted predicates the tasks of a network need."""

    def __init__(self, domain: S.Domain):
        self.preds = _never_added(domain)
        self.needs: dict = _summaries(domain, self.preds) if self.preds else {}
        self.uses: dict = _uses(domain, self.needs)

    def __bool__(self) -> bool:
        return bool(self.needs)

    def broken(self, change, state, root, cursor=None) -> bool:
        """After an action: True if it deleted an atom that a task left in
        the network (below ``root``) needs."""
        preds = self.preds
        for pred, args, _i in change.deleted:
            if (
                pred in preds
                and not state.has(pred, args)
                and self._needed(root, cursor, pred, args)
            ):
                return True
        return False

    def refused(self, subtasks: list, state, root) -> bool:
        """After a reduction: True if one of the new ``subtasks`` needs an
        atom that is gone, or is an action that uses up (needs and deletes)
        an atom that another action left in the network (below ``root``) uses
        up too: whichever runs first takes it from the other."""
        needs = self.needs
        for sub in subtasks:
            task = sub.task
            if task is None or task.name not in needs:
                continue
            for pred, pattern in needs[task.name]:
                args = _fixed(pattern, task.args)
                if args is not None and not state.has(pred, args):
                    return True
            for pred, pattern in self.uses.get(task.name, ()):
                args = _fixed(pattern, task.args)
                if args is not None and self._used(root, task, pred, args):
                    return True
        return False

    def _used(self, root, task, pred: str, args: tuple) -> bool:
        others = (t for t in _pending_tasks(root) if t is not task)
        return _any_task(others, self.uses, pred, args)

    def _needed(self, root, cursor, pred: str, args: tuple) -> bool:
        tasks = _after(cursor) if cursor else _pending_tasks(root)
        return _any_task(tasks, self.needs, pred, args)


def _any_task(tasks, table: dict, pred: str, args: tuple) -> bool:
    """Whether one of ``tasks`` has, in ``table``, a pattern giving the atom."""
    for task in tasks:
        for tpred, pattern in table.get(task.name, ()):
            if tpred == pred and _fixed(pattern, task.args) == args:
                return True
    return False


def _fixed(pattern: tuple, task_args: tuple):
    """The atom's arguments a pattern gives for a task, or None if one is unbound."""
    out = []
    for p in pattern:
        if type(p) is int:
            p = task_args[p]
            if type(p) is Var:
                return None
        out.append(p)
    return tuple(out)


def _never_added(domain: S.Domain) -> set[str]:
    """Predicates no action adds and no axiom derives, if that can be known."""
    added: set[str] = set()
    for ops in domain.operators.values():
        for op in ops:
            if op.add.var is not None:
                return set()  # an add list given by a variable: anything
            for item in op.add.items:
                atoms = item.atoms if isinstance(item, S.EffectForAll) else [item]
                for a in atoms:
                    if isinstance(a, S.VarAtom):
                        return set()
                    if isinstance(a, S.Atom):
                        added.add(a.pred)
    preds: set[str] = set()
    for ops in domain.operators.values():
        for op in ops:
            for item in op.delete.items:
                atoms = item.atoms if isinstance(item, S.EffectForAll) else [item]
                preds.update(a.pred for a in atoms if isinstance(a, S.Atom))
    return preds - added - set(domain.axioms)


def _conjuncts(pre: S.Precondition, preds: Container[str], slots: dict):
    """Positive top-level atoms of ``preds`` whose arguments are all slots or constants."""
    expr = pre.expr
    for item in expr.items if isinstance(expr, S.And) else [expr]:
        if isinstance(item, S.Atom) and item.pred in preds:
            pattern = tuple(_position(x, slots) for x in item.args)
            if None not in pattern:
                yield item.pred, pattern


def _position(x, slots: dict):
    if type(x) is Var:
        return slots.get(x.index)
    return x if type(x) in (str, float) else None


def _summaries(domain: S.Domain, preds: set[str]) -> dict:
    """task name -> {(pred, pattern)} that every way of doing it needs."""
    needs: dict = {}
    for name, ops in domain.operators.items():
        sets = []
        for op in ops:
            slots = {a.index: i for i, a in enumerate(op.head.args) if type(a) is Var}
            sets.append(set(_conjuncts(op.pre, preds, slots)))
        needs[name] = set.intersection(*sets) if sets else set()
    # compound tasks: a least fixpoint from below, each step sound
    changed = True
    while changed:
        changed = False
        for name, methods in domain.methods.items():
            sets = []
            for m in methods:
                slots = {a.index: i for i, a in enumerate(m.head.args) if type(a) is Var}
                for b in m.branches:  # branches are alternatives (HDDL: one)
                    mine = set(_conjuncts(b.pre, preds, slots))
                    for t in S.task_atoms(b.tasks):
                        for pred, pattern in needs.get(t.name, ()):
                            lifted = tuple(_lift(p, t.args, slots) for p in pattern)
                            if None not in lifted:
                                mine.add((pred, lifted))
                    sets.append(mine)
            new = set.intersection(*sets) if sets else set()
            if new != needs.get(name, set()):
                needs[name] = new
                changed = True
    return {name: tuple(ps) for name, ps in needs.items() if ps}


def _uses(domain: S.Domain, needs: dict) -> dict:
    """action name -> needed patterns that its (only) action also deletes."""
    uses = {}
    for name, ops in domain.operators.items():
        if len(ops) != 1 or name not in needs:
            continue
        deleted = set(delete_patterns(ops[0]))
        mine = tuple(p for p in needs[name] if p in deleted)
        if mine:
            uses[name] = mine
    return uses


def delete_patterns(op: S.Operator):
    """``(pred, pattern)`` of each atom of an action's plain delete list whose
    arguments are all its parameters or constants."""
    slots = {a.index: i for i, a in enumerate(op.head.args) if type(a) is Var}
    for a in op.delete.items:
        if isinstance(a, S.Atom):
            pattern = tuple(_position(x, slots) for x in a.args)
            if None not in pattern:
                yield a.pred, pattern


def _lift(p, call_args: tuple, slots: dict):
    """A callee's pattern element in the caller's terms."""
    if type(p) is not int:
        return p
    return _position(call_args[p], slots)
