"""Domain-independent heuristics for the progression search over a
grounded problem (:mod:`htn.jshop.search.grounding`).

* ``rc`` -- the **relaxed composition** heuristic of Höller, Bercher,
  Behnke and Biundo, "A Generic Method to Guide HTN Progression Search with
  Classical Heuristics" (ICAPS 2018), with h_add as the classical heuristic
  (their RC-add). The HTN problem is relaxed into a delete-free classical
  one whose facts are the state's facts and one "reached" fact per task:
  an action needs its positive preconditions and adds its effects and
  *reached(itself)*; a method needs its positive preconditions and
  *reached(s)* of each subtask and adds *reached(its task)*. The estimate
  for a search node is the h_add cost of *reached(t)* for every task ``t``
  left in the network (and of the goal's facts) from its state, with cost 1
  per action and per method, i.e. an estimate of the search steps left. A
  node with an unreachable task is a dead end (no refinement of that task
  is executable even in the relaxation), and is pruned.
* ``tdg`` -- the task decomposition graph estimate of Bercher, Behnke,
  Höller and Biundo, "An Admissible HTN Planning Heuristic" (IJCAI 2017),
  TDG_m: per task the fewest actions and methods of any refinement, computed
  once; a node's estimate is their sum over its network (state-independent).

Both are computed with Knuth's generalisation of Dijkstra's algorithm
(costs of tasks and facts are finalised cheapest first), which stops as
soon as every cost the node needs is known.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable

from .ground_formulas import bits, positive_bits
from .task_networks import tasks

INF = float("inf")
CACHED_STATES = 256  # h_add passes kept, at most
CACHE_ENTRIES = 8_000_000  # list entries the kept passes may hold, about


class _Relaxation:
    """The relaxed composition of a grounded problem as a graph of
    operators (preconditions -> effects) over facts and reached tasks."""

    def __init__(self, model, with_state: bool = True):
        nfacts = len(model.facts) if with_state else 0
        self.nfacts = nfacts
        self.nodes = nfacts + len(model.tasks)
        pres, effs = [], []
        for t, a in model.actions.items():
            pre = []
            if with_state:
                pre = bits(a.pre[0]) + [b for tree in a.pre[2] for b in positive_bits(tree)]
            eff = [nfacts + t]
            if with_state:
                eff += bits(a.possible_adds())
            pres.append(pre)
            effs.append(eff)
        for t, ms in model.methods_of.items():
            for gm in ms:
                pre = [nfacts + s for s in gm.body]
                if with_state:
                    pre += bits(gm.pre[0]) + [b for tree in gm.pre[2] for b in positive_bits(tree)]
                pres.append(pre)
                effs.append([nfacts + t])
        self.npre = [len(p) for p in pres]
        self.effects = effs
        self.free = [i for i, p in enumerate(pres) if not p]
        consumers: list = [[] for _ in range(self.nodes)]
        for i, pre in enumerate(pres):
            for n in pre:
                consumers[n].append(i)
        self.consumers = consumers

    def costs(self, sources: list) -> list:
        """h_add costs (unit operator costs) from ``sources`` (cost 0): a list
        by node, None where a node is unreachable."""
        p = _Pass(self, sources)
        p.settle(())
        return p.cost


class _Pass:
    """One h_add computation from a state, resumable: :meth:`settle`
    settles nodes cheapest first until the nodes asked for are settled, and
    a later call goes on from there (a successor network may hold a task
    the last one did not).

    Costs are whole numbers and every operator's cost exceeds those of its
    preconditions, so nodes are settled by buckets of equal cost (a heap of
    the distinct costs pending, not of the nodes): the same order as
    Dijkstra's, at a fraction of the heap operations. A whole bucket is
    settled at a time, so every node cheaper than a settled one is settled."""

    __slots__ = ("r", "cost", "acc", "left", "buckets", "keys")

    def __init__(self, r: _Relaxation, sources: list):
        self.r = r
        self.cost: list = [None] * r.nodes
        self.acc: list[int] | None = [0] * len(r.npre)
        self.left: list[int] | None = r.npre[:]
        buckets: dict = {0: list(sources)}
        if r.free:
            buckets[1] = [e for i in r.free for e in r.effects[i]]
        self.buckets = buckets
        self.keys = sorted(buckets)

    @property
    def done(self) -> bool:
        return not self.keys

    def settle(self, nodes) -> None:
        """Settle buckets until every node of ``nodes`` has a cost (all of
        them with ``()``) or nothing is left to settle."""
        cost, acc, left, buckets, keys = self.cost, self.acc, self.left, self.buckets, self.keys
        assert acc is not None and left is not None  # a finished pass is not settled again
        consumers, effects = self.r.consumers, self.r.effects
        push, pop = heapq.heappush, heapq.heappop
        pending = nodes
        while keys:
            if nodes:
                pending = [n for n in pending if cost[n] is None]
                if not pending:
                    return
            c = pop(keys)
            for n in buckets.pop(c):
                if cost[n] is not None:
                    continue
                cost[n] = c
                for i in consumers[n]:
                    acc[i] += c
                    left[i] -= 1
                    if not left[i]:
                        ci = acc[i] + 1  # > c: c is one of the summands
                        bucket = buckets.get(ci)
                        if bucket is None:
                            buckets[ci] = bucket = []
                            push(keys, ci)
                        bucket.extend(effects[i])
        self.acc = self.left = None  # finished: only the costs are kept


class RelaxedComposition:
    """RC-add (see the module docstring): ``h(state, network)``, INF for a
    dead end."""

    name = "rc"

    def __init__(self, model):
        self.relaxation = r = _Relaxation(model)
        self.goal = bits(model.goal[0]) if model.goal is not None and model.goal[0] > 0 else []
        self._passes: dict = {}  # state -> its _Pass, for the latest states
        # an unfinished pass holds two lists as long as the operators
        self.cached = max(8, min(CACHED_STATES, CACHE_ENTRIES // (2 * len(r.npre) + r.nodes + 1)))

    def __call__(self, state: int, net: tuple) -> float:
        """The costs depend on the state only: the successors that apply a
        method (all but one, in a totally ordered network) share them with
        their parent, so each state's pass is made once, and settled as far
        as the networks seen with that state need."""
        p = self._passes.get(state)
        if p is None:
            if len(self._passes) >= self.cached:
                self._passes.pop(next(iter(self._passes)))
            p = self._passes[state] = _Pass(self.relaxation, bits(state))
        nfacts = self.relaxation.nfacts
        nodes = self.goal + [nfacts + t for t in tasks(net)]
        if not p.done:
            p.settle(nodes)
        cost = p.cost
        total = 0
        for n in nodes:
            c = cost[n]
            if c is None:
                return INF
            total += c
        return total


class TaskDecompositionGraph:
    """TDG_m (see the module docstring): state-independent, ``h(state,
    network)`` is the sum of the precomputed task costs."""

    name = "tdg"

    def __init__(self, model):
        r = _Relaxation(model, with_state=False)
        cost = r.costs([])
        self.cost = [INF if cost[t] is None else cost[t] for t in range(len(model.tasks))]

    def __call__(self, state: int, net: tuple) -> float:
        cost = self.cost
        return sum(cost[t] for t in tasks(net))


# h(state, network): the estimate, INF for a dead end
Heuristic = Callable[[int, tuple], float]

HEURISTICS: dict[str, Callable[..., Heuristic]] = {
    "rc": RelaxedComposition,
    "tdg": TaskDecompositionGraph,
}
