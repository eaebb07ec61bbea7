"""Goal chains: cut a search node whose network cannot, in its order, make
the goal's hard-to-reach facts true (for the heuristic search over a
grounded problem).

A plan recognition problem compiled into HTN planning (IPC 2020's
Monroe-Partially-Observable) has a goal fact ``l7`` that only the last
observed action adds, and that action needs ``l6``, which only the one
before it adds, and so on: the observations must appear in the plan, in
their order. RC-add (:mod:`.heuristics`) lets any action of the domain
take part in its relaxation, so it cannot tell a top-level method whose
refinements hold those actions, in that order, from one whose refinements
do not; the search spends its time in the wrong ones.

The *chain facts* are the goal's positive facts and, to a fixpoint, each
positive precondition of an action that adds a chain fact, when at most
:data:`FEW` actions add it; the *chain actions* are every action that adds
a chain fact. For a ground task ``t`` and a set ``S`` of chain facts that
hold, ``after(t, S)`` over-approximates the chain facts that can hold once
some refinement of ``t`` is done: the refinement's actions are taken in
their order, deletes and every other fact ignored; a chain action whose
chain preconditions are not in the set cannot be taken, so a refinement
that needs it is impossible; ``None`` when no refinement is possible.
It is a least fixpoint over the task decomposition graph, computed on
demand for the pairs ``(t, S)`` a query reaches (a worklist, like the
grammar problem's Knuth-style fixpoints), and kept.

A node's network is then folded in its order from the state's chain
facts; the node is cut if a task gives ``None`` or the goal's chain facts
are not all reached. Where tasks are not totally ordered (a group of the
network, a partially ordered method body) their refinements may
interleave, and one may need what another adds halfway through: there
the fold only adds what the chain actions below them can add in any
order, and tests none of them on its own. The sets only over-approximate, and every
function is monotone, so no plan is lost. It is the order that makes this
stronger than a reachability test (which RC-add already makes).
"""

from __future__ import annotations

from .ground_formulas import bits
from .task_networks import tasks

FEW = 2  # a precondition with at most this many adders joins the chain
MAX_CHAIN = 60  # chain facts, at most (sets are small ints)
MAX_PAIRS = 200_000  # (task, set) values kept; beyond it the cut is off


class GoalChain:
    """``ok(state, network)``: False where the network cannot reach the
    goal's chain facts (see the module docstring)."""

    def __init__(self, model):
        self.model = model
        goal = model.goal[0] if model.goal is not None else 0
        adders: dict = {}
        for t, a in model.actions.items():
            for b in bits(a.possible_adds()):
                adders.setdefault(b, []).append(t)
        chain, work, acts = set(bits(goal)), list(bits(goal)), {}
        while work and len(chain) <= MAX_CHAIN:
            for t in adders.get(work.pop(), ()):
                if t not in acts:
                    acts[t] = None
                    for p in bits(model.actions[t].pre[0]):
                        if p not in chain and len(adders.get(p, ())) <= FEW:
                            chain.add(p)
                            work.append(p)
        self.active = bool(chain) and len(chain) <= MAX_CHAIN
        if not self.active:
            return
        self.bit_of = {b: i for i, b in enumerate(sorted(chain))}
        self.goal = self._small(goal)
        self.acts = {}  # chain action -> (chain preconditions, chain adds)
        for t in acts:
            a = model.actions[t]
            self.acts[t] = (self._small(a.pre[0]), self._small(a.possible_adds()))
        self.relevant, self.below = self._relevant(model)
        self.act_list = list(self.acts.values())
        self.value: dict = {}  # (task, set) -> set or None, at the fixpoint
        self.readers: dict = {}  # (task, set) -> the pairs whose value read it
        self._work: list = []

    def _small(self, mask: int) -> int:
        bit_of, out = self.bit_of, 0
        for b in bits(mask):
            i = bit_of.get(b)
            if i is not None:
                out |= 1 << i
        return out

    def _relevant(self, model):
        """The compound tasks with a chain action below them, and per task
        the chain actions below it (a mask over ``act_list``)."""
        users = model.parents()
        below: dict = {}
        for i, a in enumerate(self.acts):
            bit, work = 1 << i, [a]
            below[a] = below.get(a, 0) | bit
            while work:
                for u in users.get(work.pop(), ()):
                    if not below.get(u, 0) & bit:
                        below[u] = below.get(u, 0) | bit
                        work.append(u)
        return set(below) - set(self.acts), below

    # ------------------------------------------------------------ queries
    def ok(self, state: int, net: tuple) -> bool:
        if not self.active:
            return True
        out = self._seq(net, self._small(state), None)
        if not self.active:  # gave up during this query
            return True
        return out is not None and out & self.goal == self.goal

    def after(self, task: int, s: int):
        """``after(task, s)`` (see the module docstring)."""
        key = (task, s)
        if key not in self.value:
            self._solve(key)
        return self.value.get(key, s)

    # ------------------------------------------------------------ folds
    def _task(self, t: int, s: int, reader):
        act = self.acts.get(t)
        if act is not None:
            pre, add = act
            return s | add if s & pre == pre else None
        if t not in self.relevant:
            return s
        key = (t, s)
        if reader is None:
            if key not in self.value:
                self._solve(key)
            return self.value.get(key, s)
        self.readers.setdefault(key, set()).add(reader)
        if key not in self.value:
            self.value[key] = None
            self._work.append(key)
        return self.value[key]

    def _seq(self, seq, s, reader):
        for x in seq:
            if s is None:
                return None
            if type(x) is int:
                s = self._task(x, s, reader)
            else:
                s = self._group(x[0], s)
        return s

    def _group(self, members, s, reader=None):
        """Members in any order, interleaved: a member may need what another
        adds halfway through, so none is tested on its own. What can hold
        after the group is what the chain actions below it add, in any
        order, from ``s``."""
        below = 0
        for m in members:
            for t in tasks(m):
                below |= self.below.get(t, 0)
        return self._closure(below, s)

    def _closure(self, below: int, s: int) -> int:
        acts = [self.act_list[i] for i in bits(below)]
        grown = True
        while grown:
            grown, rest = False, []
            for pre, add in acts:
                if s & pre == pre:
                    if add & ~s:
                        s |= add
                        grown = True
                else:
                    rest.append((pre, add))
            acts = rest
        return s

    def _method(self, gm, s, reader):
        if gm.order is True or len(gm.body) <= 1:
            return self._seq(gm.body, s, reader)
        return self._group([(t,) for t in gm.body], s)

    def _solve(self, key) -> None:
        """Kleene iteration on the pairs reachable from ``key``: values
        start at None and only grow, and a pair is worked again when a pair
        it read has grown. A fold may read a pair that is new (None for
        now) where it read a smaller one before, so an evaluation can come
        out smaller than the value: the value keeps the union, which stays
        sound (at the end every value holds its own evaluation from the
        final values, so by induction on a refinement's height it holds
        what the refinement can reach) and makes the iteration end."""
        methods_of, value, readers = self.model.methods_of, self.value, self.readers
        value[key] = None
        self._work = work = [key]
        while work:
            k = work.pop()
            t, s = k
            out = value[k]
            for gm in methods_of.get(t, ()):
                r = self._method(gm, s, k)
                if r is not None:
                    out = r if out is None else out | r
            if out != value[k]:  # grown: what read it is worked again
                value[k] = out
                work.extend(readers.get(k, ()))
            if len(value) > MAX_PAIRS:  # too many sets of chain facts: give up
                self.active = False
                self.value, self.readers, self._work = {}, {}, []
                return
