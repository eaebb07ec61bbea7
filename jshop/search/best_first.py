"""Heuristic progression search over grounded task networks: greedy
best-first (GBFS) and weighted A* (Höller, Bercher, Behnke and Biundo,
"HTN Planning as Heuristic Progression Search", JAIR 2020; the search of
PANDA and of PandaDealer, the IPC 2023 total-order winner).

A search node is a state (an ``int`` of fact bits) and a task network
(:mod:`htn.jshop.search.task_networks`). Its successors: for every task
that may be done next, an action applied (when its precondition holds) or
a method applied (when its precondition holds in the current state: HDDL
binds and tests a method's parameters when it is applied, as the
depth-first search does). A node whose network is empty is a plan if the
problem's goal holds. Nodes are ordered by ``h`` (GBFS) or ``g + w * h``
(weighted A*, ``g`` the number of actions and methods applied), ties first
in, first out, or last in, first out where some network of the problem is
partially ordered (:func:`interleaves`); a node whose ``(state, network)``
was reached before (with no smaller ``g``) is dropped (duplicate
detection), and so is one whose network cannot make the goal's chain true
in its order (:mod:`htn.jshop.search.goal_chain`) or cannot bring in an
action that adds a missing goal fact (:mod:`htn.jshop.search.goal_reach`). When a task that may be
done next has only methods that test nothing, it is decomposed as the only
move (:func:`committed`). With ``serial``, a move into a member of an
unordered group (other than such a decomposition) first orders that member
before the group's others (:func:`~.task_networks.serialize`): a started
member is finished before another starts. That search is not complete (a
plan may need an interleaving), and the portfolio runs it beside the
others.

:meth:`BestFirst.plans` is a stream like :meth:`Planner.plans
<htn.jshop.search.planner.Planner.plans>`; with ``slice_s`` set it also
yields None each time it has used that much CPU time, so that a portfolio
can interleave it with another search (:mod:`htn.jshop.search.portfolio`).
"""

from __future__ import annotations

import heapq
import time
from collections.abc import Generator
from typing import TYPE_CHECKING

from htn.jshop.language import syntax as S
from htn.jshop.plans.plan import Plan, Step
from htn.jshop.plans.tree import TaskTree, sibling_paths

from .goal_cuts import Cut, goal_cuts
from .ground_formulas import holds, satisfied
from .grounding import UNREACHABLE_GOAL, ground, grounding_steps
from .heuristics import HEURISTICS, INF
from .limits import MemoryGuard, MemoryLimit
from .stats import Stats
from .task_networks import body_items, firsts, item_at, replace, serialize

if TYPE_CHECKING:
    from .grounding import GroundModel
    from .heuristics import Heuristic

WASTAR_WEIGHT = 2.0  # --search wastar: f = g + 2 h


class BestFirst:
    """GBFS (``weight=None``) or weighted A* on one problem instance."""

    def __init__(
        self,
        domain: S.Domain,
        instance: S.ProblemInstance,
        heuristic: str = "rc",
        weight: float | None = None,
        max_memory: int | None = None,
        tree_paths: bool = True,
        label: str = "gbfs",
        commit: bool = True,
        ties: str | None = None,
        serial: bool = False,
        split: bool = True,
        **_ignored,
    ):
        self.domain, self.instance = domain, instance
        self.heuristic_name = heuristic
        self.label = label
        self.weight = weight
        self.max_memory = max_memory
        self.tree_paths = tree_paths
        self.stats = Stats()
        self.slice_s: float | None = None  # CPU seconds between pauses, see plans()
        self.model: GroundModel | None = None
        self.h: Heuristic | None = None  # the heuristic, once grounded
        self.cut: Cut | None = None  # the goal cuts (None: off), once grounded
        self.generated = 0
        self.commit = commit  # the rule of committed() (False: every move)
        self.ties = ties  # "fifo", "lifo", None: see interleaves()
        self.lifo = False
        self.serial = serial  # a started member of a group is finished before the others
        self.split = split  # ground with parameter splitting (splitting.py)

    def prepare(self) -> None:
        """Ground the problem and build the heuristic (the first call of
        :meth:`plans` does it otherwise)."""
        if self.model is None:
            self._prepared(ground(self.domain, self.instance, self.split))

    def _prepared(
        self, model: GroundModel, h: Heuristic | None = None, cut: Cut | None = None
    ) -> None:
        """Take a grounded model (and the heuristic and goal-chain cut
        another search built on it, to share their caches)."""
        self.model = model
        self.h = h if h is not None else HEURISTICS[self.heuristic_name](model)
        self.cut = cut if cut is not None else goal_cuts(model)
        self.free = free_tasks(model) if self.commit else frozenset()
        self.lifo = interleaves(model) if self.ties is None else self.ties == "lifo"

    # ------------------------------------------------------------ search
    def plans(self, timeout: float | None = None) -> Generator[Plan | None, None, None]:
        """Plans as they are found (see the module docstring); ``timeout``
        is wall-clock time since the start, like the depth-first search's."""
        stats = self.stats
        stats.started = time.perf_counter()
        cpu = time.process_time
        pause_at = cpu() + self.slice_s if self.slice_s is not None else None
        if self.model is None:  # grounding pauses and times out like the search
            steps = grounding_steps(self.domain, self.instance, self.split)
            while True:
                try:
                    next(steps)
                except StopIteration as done:
                    self._prepared(done.value)
                    break
                if pause_at is not None and cpu() >= pause_at:
                    yield None
                    assert self.slice_s is not None  # the portfolio sets it before each turn
                    pause_at = cpu() + self.slice_s
                if timeout is not None and time.perf_counter() - stats.started > timeout:
                    stats.timed_out = True
                    return
        model, h, w = self.model, self.h, self.weight
        assert model is not None and h is not None  # set by _prepared
        actions, methods_of = model.actions, model.methods_of
        net0 = body_items(model.roots, model.root_order)
        cut, free, serial = self.cut, self.free, self.serial
        if model.goal == UNREACHABLE_GOAL:
            h0 = INF
        else:
            h0 = h(model.init, net0) if cut is None or cut.ok(model.init, net0) else INF
        # per node: (state, network, parent, move, g); move = (path, action or method)
        nodes = [(model.init, net0, -1, None, 0)]
        seen = {(model.init, net0): 0}
        heap = [(h0 if w is None else w * h0, 0, 0)] if h0 < INF else []
        ticks = 0
        guard = None
        try:
            while heap:
                _f, _tie, k = heapq.heappop(heap)
                s, net, _parent, _move, g = nodes[k]
                if seen.get((s, net), g) < g:
                    continue  # reached again more cheaply (weighted A*)
                if not net:
                    if model.goal is None or satisfied(model.goal, s):
                        stats.plans_found += 1
                        stats.elapsed = time.perf_counter() - stats.started
                        yield self._plan(nodes, k, stats.plans_found - 1)
                        continue
                    continue
                stats.expansions += 1
                ticks += 1
                for path, t in committed(firsts(net), free):
                    at, where = net, path
                    if serial and path and t not in free:
                        at, where = serialize(net, path)
                    a = actions.get(t)
                    if a is not None:
                        if not satisfied(a.pre, s):
                            continue
                        s2 = _apply(a, s)
                        stats.operator_applications += 1
                        self._push(nodes, heap, seen, s2, replace(at, where, ()), k, (path, a), g)
                        continue
                    for gm in methods_of.get(t, ()):
                        if satisfied(gm.pre, s):
                            new = body_items(gm.body, gm.order)
                            self._push(
                                nodes, heap, seen, s, replace(at, where, new), k, (path, gm), g
                            )
                if not ticks & 7:  # an RC-add pass can take 50 ms: check often
                    if timeout is not None and time.perf_counter() - stats.started > timeout:
                        stats.timed_out = True
                        return
                    if pause_at is not None and cpu() >= pause_at:
                        stats.elapsed = time.perf_counter() - stats.started
                        yield None
                        assert self.slice_s is not None  # the portfolio sets it before each turn
                        pause_at = cpu() + self.slice_s
                    if not ticks & 1023:
                        guard = guard or MemoryGuard(self.max_memory)
                        if guard.exceeded():
                            stats.bound = MemoryLimit(guard.limit_bytes, None)
                            return
        finally:
            stats.elapsed = time.perf_counter() - stats.started

    def _push(self, nodes, heap, seen, s, net, parent, move, g) -> None:
        g += 1
        key = (s, net)
        old = seen.get(key)
        if old is not None and (self.weight is None or old <= g):
            return
        seen[key] = g
        self.generated += 1
        if self.cut is not None and not self.cut.ok(s, net):
            self.stats.goal_cuts += 1
            return
        h = self.h
        assert h is not None  # set by _prepared before the search
        hv = h(s, net)
        if hv == INF:
            return
        nodes.append((s, net, parent, move, g))
        f = hv if self.weight is None else g + self.weight * hv
        heapq.heappush(heap, (f, -len(nodes) if self.lifo else len(nodes), len(nodes) - 1))

    # ------------------------------------------------------------ the plan
    def _plan(self, nodes, k: int, index: int) -> Plan:
        """The plan of goal node ``k`` with its task tree: the moves from the
        root are replayed on a network of task instances."""
        moves = []
        while k > 0:
            _s, _net, parent, move, _g = nodes[k]
            moves.append(move)
            k = parent
        moves.reverse()
        model = self.model
        assert model is not None  # a plan is found after grounding
        inst = list(model.roots)  # instance -> task id
        net = body_items(tuple(range(len(inst))), model.root_order)
        how: dict = {}  # instance -> step index or (method, children)
        steps: list[Step] = []
        free = self.free
        for path, what in moves:
            i = item_at(net, path)
            if self.serial and path and inst[i] not in free:
                net, path = serialize(net, path)
            if hasattr(what, "op"):
                how[i] = len(steps)
                steps.append(Step(what.name, what.args, what.cost))
                net = replace(net, path, ())
            else:
                kids = tuple(range(len(inst), len(inst) + len(what.body)))
                inst.extend(what.body)
                how[i] = (what, kids)
                net = replace(net, path, body_items(kids, what.order))
        plan = Plan(steps, sum(s.cost for s in steps), index=index)
        plan.tree = self._tree(inst, how, len(model.roots))
        return plan

    def _tree(self, inst: list, how: dict, nroots: int) -> TaskTree:
        assert self.model is not None  # a plan is found after grounding
        tasks = self.model.tasks
        root = TaskTree(name="", path="")
        work = [(root, tuple(range(nroots)), "", 1)]
        while work:
            parent, kids, prefix, depth = work.pop()
            kids = self._spliced(kids, inst, how)
            names = [tasks[inst[i]][0] for i in kids]
            paths = sibling_paths(prefix, names, depth) if self.tree_paths else [""] * len(kids)
            for i, name, path in zip(kids, names, paths):
                node = TaskTree(name=name, args=tasks[inst[i]][1], path=path)
                h = how.get(i)
                if type(h) is int:
                    node.step = h
                elif h is not None:
                    gm, sub = h
                    m = gm.method
                    node.method = m.name
                    node.method_index = next(
                        (j for j, x in enumerate(self.domain.methods.get(m.name, ())) if x is m), 0
                    )
                    node.branch = m.branches[gm.branch].label
                    work.append((node, sub, path, depth + 1))
                parent.children.append(node)
        return root

    def _spliced(self, kids: tuple, inst: list, how: dict) -> tuple:
        """The children of a tree node, each task that parameter splitting
        made (:mod:`.splitting`) replaced by its own children."""
        assert self.model is not None  # a plan is found after grounding
        tasks, hidden = self.model.tasks, self.model.hidden
        if not hidden or not any(tasks[inst[i]][0] in hidden for i in kids):
            return kids
        out: list = []
        for i in kids:
            if tasks[inst[i]][0] in hidden:
                out += self._spliced(how[i][1], inst, how)
            else:
                out.append(i)
        return tuple(out)


def free_tasks(model) -> frozenset:
    """The compound tasks whose ground methods all have a true precondition
    (static facts were compiled away in grounding): decomposing one of them
    commutes with every other move, see :func:`committed`."""
    return frozenset(t for t, ms in model.methods_of.items() if all(gm.pre == _TRUE for gm in ms))


_TRUE = (0, 0, ())


def committed(front: list, free: frozenset) -> list:
    """The moves a node branches over: when a task that may be done next is
    in ``free``, only its methods (the first such task in ``front``), else
    every task of ``front``.

    Complete: a plan below the node decomposes that task at some point, and
    the decomposition can be moved to the front of the plan's moves, since
    no move in between is below the task, none needs it finished (it was
    not), and the methods' preconditions hold in every state. This is the
    rule of Höller et al. (JAIR 2020) that the decision which abstract task
    to decompose next is no choice point, kept to tasks whose methods test
    nothing of the state: a method's precondition is tested when it is
    applied, and postponing that is a choice. Total-order networks have one
    task in ``front``, so nothing changes for them; on partially ordered
    ones it saves the interleavings of decompositions (ipc-po Transport
    pfile04: GBFS finds a plan after 258 k expansions, 5.5 s of CPU; without
    the rule it finds none in 40 s, 1.3 M expansions).
    """
    if len(front) > 1:
        for move in front:
            if move[1] in free:
                return [move]
    return front


def interleaves(model) -> bool:
    """Whether some network of the problem is partially ordered (its
    initial network or a method's body): ties between nodes of equal
    ``f`` are then broken last in, first out, else first in, first out.

    Nodes of equal ``f`` in a partially ordered problem are mostly the
    same moves interleaved in other orders; first in, first out takes them
    breadth-first, every interleaving of every prefix, where last in, first
    out follows one (ipc-po Colouring pfile19: GBFS with FIFO ties found
    no plan in 30 s of CPU, with LIFO in 4.5 s; Transport pfile04 and
    Colouring pfile20 are solved either way). Total-order problems keep FIFO: there
    ties are other decompositions, and LIFO loses the plan of
    AssemblyHierarchical depth13 (2.6 s with FIFO, none in 30 s)."""

    def partial(items, order):
        return len(items) > 1 and order is not True

    if partial(model.roots, model.root_order):
        return True
    return any(partial(gm.body, gm.order) for ms in model.methods_of.values() for gm in ms)


def _apply(a, s: int) -> int:
    """PDDL's semantics: conditions in the state before, deletes, then adds."""
    dels, adds = a.dels, a.adds
    for cond, d, more in a.effects:
        pos, neg, rest = cond
        if s & pos == pos and not s & neg and all(holds(x, s) for x in rest):
            dels |= d
            adds |= more
    return (s & ~dels) | adds
