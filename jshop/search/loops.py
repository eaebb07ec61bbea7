"""Loop detection for total-order HTN search (used for HDDL domains).

IPC domains are recursive, and plain depth-first decomposition can recurse
without end: Transport's ``get_to`` reduces to ``get_to`` of a neighbour
first, Hiking's ``trip_to2`` to itself, Entertainment's ``a_connect ?e1 ?e3``
to ``a_connect ?e1 ?e2`` for any ``?e2``. HyperTensioN ("dejavu", Magnaguagno
et al., IPC 2020) refuses to decompose a recursive task again while an
identical one is still being decomposed; this planner does the same with the
state added, so that recursion that makes progress (Towers' moves, a snake's
walk) is never cut:

    a task instance (name and arguments) is not reduced in a state while the
    same task, reduced in the same state, is an ancestor in the decomposition
    (it is still "active": reduced, its subtasks not all achieved).

A loop cut this way would only repeat, below itself, a decomposition of the
same task from the same state, which the ancestor can choose itself. The
search then terminates on every problem with finitely many objects: an
infinite branch would repeat some task and state on one ancestor chain. It
is not complete for every HTN problem (a plan that needs a task to re-enter
itself in an unchanged state is lost), which is the trade-off total-order
planners make. Keying on the task rather than on the method instance (the
method and the binding of all its variables) matters for left recursion with
a free variable: Entertainment's ``a_connect`` chains are bounded by the
number of equipment objects, not by the number of (intermediate, target)
pairs.

States are compared by an incremental hash (:class:`~htn.jshop.logic.state.HashedState`).
"Active" is tracked with the planner's own bookkeeping: a reduced node is
active from its reduction until :func:`~htn.jshop.search.planner.first_tasks` marks
it done, and again if that mark is undone on backtracking.
"""

from __future__ import annotations


class LoopCheck:
    """The active task instances of the current search path."""

    __slots__ = ("state", "active", "cut")

    def __init__(self, state):
        self.state = state  # a HashedState
        self.active: dict = {}  # key -> count
        self.cut = 0  # reductions refused

    def key(self, task) -> tuple:
        return (task.name, task.args, self.state.key)

    def is_loop(self, node, key) -> bool:
        """Whether reducing ``node`` with an active ``key`` would loop: in a
        totally ordered network every active task is an ancestor."""
        return True

    def enter(self, node, key) -> None:
        node.loop_key = key
        self.active[key] = self.active.get(key, 0) + 1

    def leave(self, node) -> None:
        self._drop(node.loop_key)
        node.loop_key = None

    def completed(self, trail: list, start: int) -> None:
        """Nodes that ``first_tasks`` marked done since ``start`` are no longer active."""
        for i in range(start, len(trail)):
            entry = trail[i]
            if type(entry) is not tuple and entry.loop_key is not None:
                self._drop(entry.loop_key)

    def reopened(self, node) -> None:
        """A done mark was undone: the node is active again."""
        if node.loop_key is not None:
            self.active[node.loop_key] = self.active.get(node.loop_key, 0) + 1

    def _drop(self, key) -> None:
        n = self.active[key]
        if n <= 1:
            del self.active[key]
        else:
            self.active[key] = n - 1
