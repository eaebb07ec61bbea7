"""Hierarchical reachability: the facts and tasks a grounded problem can
reach when only the actions its task hierarchy can bring in are applied.

Grounding's first step (:mod:`.reachability`) applies every action of the
domain under the delete relaxation. A plan, though, only applies actions
that some decomposition of the initial task network brings in, and only
applies a method whose precondition holds. This module computes the least
fixpoint of both at once:

* a task is reached if it is in the initial network or in the body of a
  reached method;
* a method is reached if its task is reached and the positive literals of
  its precondition are reached facts;
* an action is reached if its task is reached and the positive literals of
  its precondition are reached facts, and then every fact it may add is
  reached (conditional effects as if their conditions held).

Negative literals are taken as true (and a disjunction holds where one of
its parts does), so every method and action on the way to a plan is
reached: a progression search applies its moves one after another, each in
a state of the initial facts and of what earlier actions added, each
decomposing a task of the initial network or of an earlier method's body
(totally or partially ordered alike).

Grounding runs it while it instantiates (:class:`Reach`): the subtasks of
the methods reached are instantiated first, so that a problem whose initial
network is out of reach is decided before the rest is grounded (see
``SKIPPED`` in :mod:`.grounding`). This is what decides IPC
2020's Minecraft-Player: the delete relaxation of ``walk`` puts the player
on every empty cell of every level, and grounding made a ``findway`` task
for each of them (386k tasks in 40 s on ``p-006-006-006-006``), but the
methods only walk it along ``neighbour`` cells of its own level, so the
roofs of houses higher than 4 are out of reach and the problem has no plan.
What is not reached can be dropped, but grounding keeps it where a plan is
possible: see :mod:`.grounding`.
"""

from __future__ import annotations

from .ground_formulas import bits


class Reach:
    """The fixpoint, grown as the caller offers what it grounds: each
    compound task's methods (:meth:`methods_of`), each action task's action
    (:meth:`action`); :meth:`take` gives the subtasks of the methods reached
    since, which the caller grounds next."""

    def __init__(self, init: int):
        self.facts = init  # the reached facts (a mask)
        # each reached method (the objects: an id could be given again to a
        # new method once a list of methods that was replaced is freed)
        self.methods: set = set()
        self.actions: set = set()  # task id of each reached action
        self.waiting: dict = {}  # fact bit -> the (task, method or action) that wait for it
        self.on_trees: set = set()  # those that wait for every fact of their trees
        self.offered: list = []  # (task, method or action) to look at
        self.subtasks: list = []  # of the methods reached, not taken yet

    def action(self, t: int, a) -> None:
        self.offered.append((t, a))

    def methods_of(self, t: int, ms) -> None:
        self.offered += [(t, m) for m in ms]

    def take(self) -> list:
        """The subtasks of the methods reached (with what was offered)."""
        while self.offered:
            offered, self.offered = self.offered, []
            new = 0
            for t, item in offered:
                pos, _neg, rest = item.pre
                if pos & ~self.facts or not all(_relaxed(tree, self.facts) for tree in rest):
                    self._wait(t, item)
                elif hasattr(item, "body"):  # a method
                    if item not in self.methods:
                        self.methods.add(item)
                        self.subtasks += item.body
                elif t not in self.actions:
                    self.actions.add(t)
                    new |= item.possible_adds()
            new &= ~self.facts
            if new:
                self.facts |= new
                self.offered = [x for b in bits(new) for x in self.waiting.pop(b, ())]
        out, self.subtasks = self.subtasks, []
        return out

    def _wait(self, t: int, item) -> None:
        """Register ``item`` with a fact it lacks: the lowest of its positive
        literals, else every positive fact of the trees it fails (once: one
        of those must come before they can hold)."""
        missing = item.pre[0] & ~self.facts
        if missing:
            low = (missing & -missing).bit_length() - 1
            self.waiting.setdefault(low, []).append((t, item))
        elif item not in self.on_trees:
            self.on_trees.add(item)
            for tree in item.pre[2]:
                for b in _positive(tree):
                    if not self.facts >> b & 1:
                        self.waiting.setdefault(b, []).append((t, item))


def reached(model) -> tuple[int, set, set]:
    """``(facts, methods, actions)`` of a grounded model: the reached facts
    (a mask), and the reached methods and actions (by task id)."""
    r = Reach(model.init)
    todo, seen = list(model.roots), set(model.roots)
    while todo:
        for t in todo:
            a = model.actions.get(t)
            if a is not None:
                r.action(t, a)
            else:
                r.methods_of(t, model.methods_of.get(t, ()))
        todo = []
        for s in r.take():
            if s not in seen:
                seen.add(s)
                todo.append(s)
    return r.facts, r.methods, r.actions


def _relaxed(tree, facts: int) -> bool:
    """A residual tree under the delete relaxation: its negative literals
    hold, its positive ones where the fact is reached."""
    kind = tree[0]
    if kind == "lit":
        return not tree[2] or bool(facts >> tree[1] & 1)
    if kind == "and":
        return all(_relaxed(x, facts) for x in tree[1])
    return any(_relaxed(x, facts) for x in tree[1])


def _positive(tree) -> list:
    """The facts of a tree's positive literals."""
    if tree[0] == "lit":
        return [tree[1]] if tree[2] else []
    return [b for x in tree[1] for b in _positive(x)]
