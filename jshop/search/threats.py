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

from itertools import chain

from htn.jshop.language import syntax as S
from htn.jshop.language.terms import Var

from .goals import _pending_tasks
from .needs import _conjuncts, _fixed, delete_patterns


class ThreatOrder:
    """Reorders a method's bindings so that threatening ones come last."""

    def __init__(self, domain: S.Domain):
        self.needs: dict = {}
        self.dels: dict = {}
        deleted: set[str] = set()
        for name, ops in domain.operators.items():
            if len(ops) != 1:
                continue
            dels = tuple(delete_patterns(ops[0]))
            if dels:
                self.dels[name] = dels
                deleted.update(pred for pred, _pattern in dels)
        # only atoms some action deletes can be threatened
        for name, ops in domain.operators.items():
            if len(ops) == 1:
                op = ops[0]
                slots = {a.index: i for i, a in enumerate(op.head.args) if type(a) is Var}
                needs = tuple(_conjuncts(op.pre, deleted, slots))
                if needs:
                    self.needs[name] = needs

    def __bool__(self) -> bool:
        return bool(self.needs and self.dels)

    def order(self, bindings, reduce, state, root):
        """The bindings in threat order, lazily: a binding that threatens
        nothing is passed on as it comes, the others (copied) after the
        last one."""
        bindings = iter(bindings)
        first = next(bindings, None)
        if first is None:
            return
        first = first[:]  # the satisfier may reuse its list for the next one
        second = next(bindings, None)
        if second is None:  # one binding: nothing to reorder
            yield first
            return
        dels = self.dels
        wanted: dict = {}  # atom -> whether a primitive task left in the network needs it
        later = []
        for nb in chain((first, second), bindings):
            taken = []
            for sub in reduce(nb):
                task = sub.task
                if task is not None and task.name in dels:
                    for pred, pattern in dels[task.name]:
                        args = _fixed(pattern, task.args)
                        if args is not None and state.has(pred, args):
                            taken.append((pred, args))
            if taken:
                unknown = [atom for atom in taken if atom not in wanted]
                if unknown:
                    self._look_up(root, unknown, wanted)
            if any(wanted[atom] for atom in taken):
                later.append(nb[:])
            else:
                yield nb
        yield from later

    def _look_up(self, root, atoms: list, wanted: dict) -> None:
        """Record in ``wanted`` whether a primitive task left in the network
        needs each of ``atoms``."""
        for atom in atoms:
            wanted[atom] = False
        preds = {pred for pred, _args in atoms}
        needs = self.needs
        for task in _pending_tasks(root):
            for pred, pattern in needs.get(task.name, ()):
                if pred in preds:
                    atom = (pred, _fixed(pattern, task.args))
                    if atom in wanted:
                        wanted[atom] = True
