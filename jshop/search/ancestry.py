"""Loop detection when tasks interleave (partially ordered networks).

The loop check of :mod:`htn.jshop.search.loops` refuses to reduce a task in
a state while the same task, reduced in the same state, is still active. In
a totally ordered network every active task is an ancestor of the task
being reduced, which is what the rule means. When tasks interleave (HDDL
``:ordering`` that leaves subtasks unordered, ``:subtasks`` with none, or
an unordered initial task network), an active task may be a cousin instead:
two ``deliver`` tasks of Transport both reduce ``(get_to truck l)`` from the
same state, and cutting the second would lose every plan. Here the rule is
applied to ancestors only: each node of a reduced task's body remembers the
chain of loop keys above it.
"""

from __future__ import annotations

from htn.jshop.language import syntax as S

from .loops import LoopCheck


class AncestorLoopCheck(LoopCheck):
    """The loop check on the ancestors of the task being reduced."""

    __slots__ = ("chains",)

    def __init__(self, state):
        super().__init__(state)
        # id(node) -> (node, chain): the chain (key, parent's chain) of its
        # ancestors, beside the node itself, so that an id Python gives again
        # to a new node never finds the chain of one that was freed
        self.chains: dict = {}

    def is_loop(self, node, key) -> bool:
        """Whether an ancestor of ``node`` was reduced with ``key`` (a key
        known to be active)."""
        chain = self._chain(node)
        while chain is not None:
            if chain[0] == key:
                return True
            chain = chain[1]
        return False

    def _chain(self, node):
        hit = self.chains.get(id(node))
        return hit[1] if hit is not None and hit[0] is node else None

    def enter(self, node, key) -> None:
        super().enter(node, key)
        chain = (key, self._chain(node))
        for child in node.subtasks:
            self.chains[id(child)] = (child, chain)

    def leave(self, node) -> None:
        super().leave(node)
        for child in node.subtasks:
            self.chains.pop(id(child), None)


def interleaves(domain: S.Domain, instance: S.ProblemInstance) -> bool:
    """Whether any task list of the domain or the problem is not totally ordered."""
    if not instance.tasks.ordered:  # also the body of an HDDL root task
        return True
    return any(
        not b.tasks.ordered
        for ms in domain.methods.values()
        for m in ms
        for b in m.branches
        if len(b.tasks.items) > 1
    )


def loop_check_for(domain: S.Domain, instance: S.ProblemInstance, state) -> LoopCheck:
    """The loop check for a problem: on ancestors only when tasks interleave."""
    return (AncestorLoopCheck if interleaves(domain, instance) else LoopCheck)(state)
