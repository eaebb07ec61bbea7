"""Threat ordering: try last the method bindings that take what a later action needs.

When a method has several bindings, depth-first search tries them in the
order the precondition's satisfiers come in. A binding whose actions delete
an atom that an action still waiting in the network needs (a causal link,
in partial-order planning's terms, that the binding threatens) is seldom the
one that leads to a plan: Factories-simple's ``deliver_resource`` may pick a
resource up from any place where one lies, including one where it waits for
a ``fuse``; the fuse then fails hundreds of actions later, and chronological
backtracking takes exponential time to get back to that choice.

So, for HDDL, the bindings of a method are put in two groups, stably: those
whose own actions (the method's primitive subtasks) delete no atom that
holds now and that a primitive task left in the network needs, then the
others. Nothing is cut, so no plan is lost; only the order changes.

What an action needs and deletes is summarised per action name, as patterns
over its arguments: the positive atoms of its precondition's top-level
conjunction and its unconditional delete list.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

from .goals import _pending_tasks
from .needs import _conjuncts, _fixed, _position


class ThreatOrder:
    """Reorders a method's bindings so that threatening ones come last."""

    def __init__(self, domain: S.Domain):
        self.needs: dict = {}
        self.dels: dict = {}
        for name, ops in domain.operators.items():
            if len(ops) != 1:
                continue
            op = ops[0]
            slots = {a.index: i for i, a in enumerate(op.head.args) if type(a) is Var}
            needs = tuple(_conjuncts(op.pre, _AllPreds(), slots))
            if needs:
                self.needs[name] = needs
            dels = tuple(
                (a.pred, pattern)
                for a in op.delete.items
                if isinstance(a, S.Atom)
                and None not in (pattern := tuple(_position(x, slots) for x in a.args))
            )
            if dels:
                self.dels[name] = dels

    def __bool__(self) -> bool:
        return bool(self.needs and self.dels)

    def order(self, bindings, reduce, state, root) -> list:
        """The bindings (copied) in threat order."""
        found = [nb[:] for nb in bindings]
        if len(found) < 2:
            return found
        dels = self.dels
        taken = []  # per binding: atoms its actions delete that hold now
        for nb in found:
            atoms = set()
            for sub in reduce(nb):
                task = sub.task
                if task is not None and task.name in dels:
                    for pred, pattern in dels[task.name]:
                        args = _fixed(pattern, task.args)
                        if args is not None and state.has(pred, args):
                            atoms.add((pred, args))
            taken.append(atoms)
        if not any(taken):
            return found
        wanted = self._needed(root, set().union(*taken))
        if not wanted:
            return found
        safe = [nb for nb, atoms in zip(found, taken) if not (atoms & wanted)]
        if len(safe) in (0, len(found)):
            return found
        return safe + [nb for nb, atoms in zip(found, taken) if atoms & wanted]

    def _needed(self, root, atoms: set) -> set:
        """Which of ``atoms`` a primitive task left in the network needs."""
        needs = self.needs
        out = set()
        for task in _pending_tasks(root):
            for pred, pattern in needs.get(task.name, ()):
                atom = (pred, _fixed(pattern, task.args))
                if atom in atoms:
                    out.add(atom)
        return out


class _AllPreds:
    """Every predicate (for :func:`needs._conjuncts`)."""

    def __contains__(self, pred) -> bool:
        return True
