"""Methods that cannot apply in any state the problem can reach, found before
the search (HyperTensioN's pullup step prunes the same way).

A predicate that no operator adds or deletes is *static*: its atoms are those
of the initial state, in every state. A method branch whose precondition
requires, as one of its top-level conjuncts, a static atom that no fact of
the initial state matches (same predicate, same arity, the same constants
where the literal has constants) never has a satisfier; an operator likewise.
A task none of whose operators or methods can apply cannot be done, so a
branch with such a subtask cannot be done either; this is repeated until
nothing changes. In Monroe, whose problems state no ``hazard_seriousness``,
both methods of ``clean_up_hazard`` go, then every method that needs that
task, and so on: 18 to 21 of 66 to 72 methods in all, which depth-first
search would otherwise try for every pair of points before it fails.

The pruning is sound: a pruned method has no decomposition that leads to a
plan. It is applied to HDDL input only (its preconditions are conjunctions of
literals over declared predicates, without axioms or external calls), and
not while ``--explain`` records dead ends, which then name the literal that
failed. A method keeps its place in the domain's order (``method K`` of a
task tree), so plans and their trees are those of the unpruned search.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var


def _changed(domain: S.Domain) -> set[str] | None:
    """The predicates some operator adds or deletes
    (:meth:`~htn.jshop.language.syntax.Domain.dynamic_predicates`); None when
    an effect's predicate is not known before the search (an atom in a
    variable, or an effect list in one)."""
    for ops in domain.operators.values():
        for op in ops:
            if op.add.var is not None or op.delete.var is not None:
                return None
            for effects in (op.add, op.delete):
                for item in effects.items:
                    atoms = item.atoms if isinstance(item, S.EffectForAll) else [item]
                    if any(isinstance(a, S.VarAtom) for a in atoms):
                        return None
    return domain.dynamic_predicates()


def _required(expr: Any) -> Iterator[S.Atom]:
    """The atoms a precondition requires as top-level conjuncts."""
    if isinstance(expr, S.Atom):
        yield expr
    elif isinstance(expr, S.And):
        for item in expr.items:
            yield from _required(item)


class _Facts:
    """The initial state's atoms of the static predicates."""

    def __init__(self, atoms: list[S.Atom], static: set[str], implied: dict[str, list[str]]):
        self.by_pred: dict[str, list[tuple[Any, ...]]] = {}
        for atom in atoms:
            for pred in (atom.pred, *implied.get(atom.pred, ())):
                if pred in static:
                    self.by_pred.setdefault(pred, []).append(atom.args)

    def may_hold(self, atom: S.Atom) -> bool:
        fixed = [(k, a) for k, a in enumerate(atom.args) if not isinstance(a, (Var, list, tuple))]
        n = len(atom.args)
        return any(
            len(args) == n and all(args[k] == a for k, a in fixed)
            for args in self.by_pred.get(atom.pred, ())
        )


def _impossible(pre: S.Precondition, static: set[str], facts: _Facts) -> bool:
    return any(atom.pred in static and not facts.may_hold(atom) for atom in _required(pre.expr))


def dead_methods(domain: S.Domain, instance: S.ProblemInstance) -> set[tuple[str, int]]:
    """``(task name, position in domain.methods[name])`` of every method that
    cannot apply in any state reachable from ``instance``'s initial state."""
    changed = _changed(domain)
    if changed is None or domain.language != "hddl":
        return set()
    predicates: set[str] = set()
    for ops in domain.operators.values():
        for op in ops:
            predicates.update(a.pred for a in _required(op.pre.expr))
    for ms in domain.methods.values():
        for m in ms:
            for b in m.branches:
                predicates.update(a.pred for a in _required(b.pre.expr))
    static = predicates - changed - set(domain.axioms)
    facts = _Facts([*domain.facts, *instance.state], static, domain.implied)
    live_ops = {
        name
        for name, ops in domain.operators.items()
        if any(not _impossible(op.pre, static, facts) for op in ops)
    }
    # a branch's own precondition is judged once; its subtasks as tasks die
    branch_ok = {
        (name, i): [not _impossible(b.pre, static, facts) for b in m.branches]
        for name, ms in domain.methods.items()
        for i, m in enumerate(ms)
    }
    dead: set[tuple[str, int]] = set()
    live_tasks = set(domain.methods)
    while True:

        def doable(t: S.TaskAtom, live_tasks: set[str] = live_tasks) -> bool:
            return t.name in live_ops if t.name.startswith("!") else t.name in live_tasks

        newly = {
            (name, i)
            for name, ms in domain.methods.items()
            for i, m in enumerate(ms)
            if (name, i) not in dead
            and not any(
                ok and all(doable(t) for t in S.task_atoms(b.tasks))
                for ok, b in zip(branch_ok[name, i], m.branches)
            )
        }
        if not newly:
            return dead
        dead |= newly
        live_tasks = {
            name
            for name, ms in domain.methods.items()
            if any((name, i) not in dead for i in range(len(ms)))
        }
