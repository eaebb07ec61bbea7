"""``--search auto``: depth-first and heuristic search as a portfolio.

The searches of :mod:`htn.jshop.search.searches` run in turns in one
process, and share its CPU time by fixed shares (stride scheduling: each
turn, half a second per share, goes to the search that has used the least
CPU time for its share): depth-first search 1, the greedy heuristic search
3 (grounding the problem included), and once that has grounded the
problem, on the same model, a weighted A* 1, a GBFS with TDG_m 1 (3 where
the goal has a chain, :mod:`.goal_chain`, whose cut it uses), and where some
network is partially ordered a GBFS that finishes a started member of an
unordered group before the others 1 (for 2 s of CPU in all; it leaves out
plans that need an interleaving, so its running out of moves proves
nothing). A search started late joins a turn behind the others, so that
its first turn comes at once, and then keeps their pace. Depth-first
search that has gone :data:`STRAIGHT` expansions without a backtrack gets
as much as all the others together while it stays so. JSHOP2's
depth-first search is fast where the written method order leads to a plan
(most IPC total-order domains: within a second on the shared sample, so it
goes first), the greedy best-first search with the relaxed composition
heuristic where depth-first search is stuck, and it needs the time to
ground the problem first. The first plan found wins and ``stats.found_by`` says by which.
Depth-first search with its loop check may give up; the heuristic search,
with duplicate detection on a finite grounded space, says "no plan" only
when there is none, so that answer is taken from it (or from both). When
the problem cannot be grounded
(:class:`~htn.jshop.search.ground_formulas.NotGroundable`) or the heuristic
search stops at a bound, depth-first search goes on alone. Every turn is
measured in CPU time of this process, so that what a run costs does not
depend on the machine's load.
"""

from __future__ import annotations

import time
from collections.abc import Generator, Sequence
from typing import TYPE_CHECKING

from htn.jshop.language import syntax as S

from .planner import Planner
from .stats import Stats

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Plan

    from .best_first import BestFirst

SLICE = 0.5  # CPU seconds per turn and share
TIE = SLICE / 4  # CPU seconds per share within which searches count as even
# shares of CPU time against depth-first search: gbfs, and weighted A* once gbfs has
# grounded the problem (the two share the grounded model and the heuristic's
# costs); weighted A* solves what greedy search gets lost in (ipc-po
# Transport pfile04: 27k expansions, where GBFS made 477k without a plan)
# and, where the goal has a chain (goal_chain.py), GBFS with the cheap
# TDG heuristic as long as GBFS: the cut carries the goal, and TDG_m's
# estimate costs nothing per state where an RC-add pass of a new state takes
# 0.1 s (Monroe-Partially-Observable pfile14: 10k expansions, where GBFS with
# RC-add made 1.7k in 30 s without a plan; ipc-po Monroe-PO pfile21: 74k
# expansions in 8 s, which a share of 1 left unsolved in 30 s)
# GBFS that finishes a started member of an unordered group before the
# others (BestFirst's serial; partially ordered problems only): it skips the
# interleavings that lead nowhere (ipc-po Rover: all 20 IPC 2020 instances
# within 2 s alone, where GBFS over every interleaving solved 7 in 30 s),
# but misses plans that need them (PCP), so that it running out of moves
# says nothing
SHARES = {"dfs": 1, "gbfs": 3, "wastar": 1, "gbfs-tdg": 3, "gbfs-serial": 1}
# CPU seconds the serial GBFS may use in all: where it works it needs little
# (IPC 2020's partial-order Rover: at most 0.3 s of search on 19 of the 20,
# 1.44 s on pfile20), and where it does not it slows the others down (ipc-po
# Transport pfile04, found by weighted A*: 2.47 s of CPU without it, 4.85 s
# with it unbounded)
SERIAL_BUDGET = 2.0
# GBFS with TDG_m where the goal has no chain: a cheap second opinion,
# blind to the state but fast per node, for models so large that an RC-add
# pass per state costs tens of milliseconds (IPC 2023 Snake, 4 slots, split
# (splitting.py): 176k actions; GBFS with RC-add made 512 expansions in
# 30 s, GBFS with TDG_m found a plan after 43k expansions, 1 s)
TDG_SHARE_NO_CUT = 1
# Depth-first search that has expanded this many nodes without a backtrack or
# a loop cut is on a straight path: each decomposition it chose has led on,
# so it needs CPU time in proportion to the plan's length, not luck. As long
# as it stays so, its share is that of all the others together (IPC 2020
# Towers pfile_17, 131,071 moves: 8.6 s alone, past 30 s with a share of 1,
# where the heuristic searches have no chance; a plan of that length is
# beyond their expansions)
STRAIGHT = 10_000


class Portfolio:
    """Interleaves a :class:`Planner`, a :class:`BestFirst` (GBFS) and,
    once GBFS has grounded the problem, a weighted A* on the same model
    (and a GBFS with TDG_m where the goal-chain cut is on). The heuristic
    searches are built (and their modules imported) at their first turn:
    where depth-first search finds a plan within its first slice, which is
    most small problems, none of them is."""

    def __init__(
        self,
        domain: S.Domain,
        instance: S.ProblemInstance,
        functions=None,
        max_memory: int | None = None,
        tree_paths: bool = True,
        **options,
    ):
        self.dfs = Planner(
            domain, instance, functions, max_memory=max_memory, tree_paths=tree_paths, **options
        )
        self._problem = (domain, instance)
        self._max_memory, self._tree_paths = max_memory, tree_paths
        self._made: dict[str, Planner | BestFirst] = {"dfs": self.dfs}
        self.stats = Stats()
        self.grounded = False
        self.started = 2  # searches started: dfs, gbfs, then those on its model
        self.ended: list[str] = []  # the searches that ended, in order
        self.spent: dict[str, float] = {}  # label -> CPU seconds it has used
        self.turns: list[str] = []  # who had each turn, in order

    def member(self, label: str):
        """The search ``label`` (a key of :data:`SHARES`), built at its first need."""
        search = self._made.get(label)
        if search is None:
            from .best_first import WASTAR_WEIGHT, BestFirst

            search = BestFirst(
                *self._problem,
                heuristic="tdg" if label == "gbfs-tdg" else "rc",
                weight=WASTAR_WEIGHT if label == "wastar" else None,
                max_memory=self._max_memory,
                tree_paths=self._tree_paths,
                label=label,
                serial=label == "gbfs-serial",
            )
            self._made[label] = search
        return search

    gbfs = property(lambda self: self.member("gbfs"))
    wastar = property(lambda self: self.member("wastar"))
    tdg = property(lambda self: self.member("gbfs-tdg"))
    serial = property(lambda self: self.member("gbfs-serial"))

    def plans(self, timeout: float | None = None) -> Generator[Plan, None, None]:
        live = ["dfs", "gbfs"]
        streams: dict[str, Generator[Plan | None, None, None]] = {}
        # CPU seconds each search has used; the next turn goes to the live
        # search that has used the least for its share (stride scheduling),
        # so that one started late, on GBFS's model, joins at once and at
        # the others' pace rather than after their long slices
        used = dict.fromkeys(live, 0.0)  # what it used, or had when it joined
        self.spent = dict.fromkeys(live, 0.0)
        self.stats.started = time.perf_counter()
        try:
            while live:
                if not self.grounded and "gbfs" in self._made and self.gbfs.h is not None:
                    # a turn behind the slowest: each has its first turn at once
                    pace = min(used[s] / self._share(s, live) for s in live) - SLICE
                    began = time.process_time()
                    for s in self._on_model():
                        live.append(s)
                        used[s] = pace * self._share(s, live)
                        self.spent[s] = 0.0
                    # the one heuristic built there is TDG_m's (the others share
                    # GBFS's): its CPU time is its search's (0.55 s on Freecell 04-3)
                    built = time.process_time() - began
                    used["gbfs-tdg"] += built
                    self.spent["gbfs-tdg"] += built
                # in quarter turns, so that a slice's overshoot of a few
                # milliseconds does not decide a tie: the earlier search goes
                label = min(live, key=lambda s: int(used[s] / self._share(s, live) / TIE))
                search = self.member(label)
                search.slice_s = SLICE * self._share(label, live)
                stream = streams.get(label)
                if stream is None:
                    stream = streams[label] = search.plans(timeout)
                if label == "gbfs-serial" and self.spent[label] >= SERIAL_BUDGET:
                    stream.close()  # its budget is spent: the others go on
                    live.remove(label)
                    self.ended.append(label)
                    continue
                self.turns.append(label)
                began = time.process_time()
                try:
                    plan = next(stream)
                except StopIteration:
                    live.remove(label)
                    self.ended.append(label)
                    if (
                        label not in ("dfs", "gbfs-serial")  # the serial GBFS leaves plans out
                        and not search.stats.timed_out
                        and search.stats.bound is None
                    ):
                        return  # searched the whole space: no other plan
                    if search.stats.timed_out:
                        return
                    continue
                except Exception as exc:
                    from .ground_formulas import NotGroundable

                    if not isinstance(exc, NotGroundable):
                        raise
                    live.remove(label)  # depth-first search goes on alone
                    self.ended.append(label)
                    continue
                finally:
                    cpu = time.process_time() - began
                    used[label] += cpu
                    self.spent[label] += cpu
                    self._sum()
                if plan is None:  # its slice is over: the next one's turn
                    continue
                self.stats.found_by = label
                self.stats.plans_found += 1
                plan.index = self.stats.plans_found - 1
                yield plan
        finally:
            for stream in streams.values():
                stream.close()
            self._sum()

    def _share(self, label: str, live: Sequence[str] = ()) -> float:
        """``label``'s share of the CPU time among the ``live`` searches."""
        if label == "dfs" and self._straight():
            return max(SHARES["dfs"], sum(self._share(s) for s in live if s != "dfs"))
        if label == "gbfs-tdg":
            from .goal_cuts import chained

            if not chained(self.tdg.cut):
                return TDG_SHARE_NO_CUT
        return SHARES[label]

    def _straight(self) -> bool:
        """Has depth-first search made :data:`STRAIGHT` expansions without a
        backtrack or a loop cut?"""
        stats, loops = self.dfs.stats, self.dfs.loops
        return (
            stats.backtracks == 0
            and (loops is None or loops.cut == 0)
            and stats.expansions >= STRAIGHT
        )

    def _on_model(self) -> list[str]:
        """The searches to start once GBFS has grounded the problem, on its
        model (and its heuristic's costs and goal-chain cut, shared)."""
        from .best_first import interleaves

        self.grounded = True
        g = self.gbfs
        assert g.model is not None  # grounded: its heuristic is built
        more = []
        if interleaves(g.model):  # first: where it works it needs little
            self.serial._prepared(g.model, g.h, g.cut)
            more.append("gbfs-serial")
        self.wastar._prepared(g.model, g.h, g.cut)
        more.append("wastar")
        self.tdg._prepared(g.model, None, g.cut)
        more.append("gbfs-tdg")
        self.started += len(more)
        return more

    def _sum(self) -> None:
        """The portfolio's statistics: both searches' work added up."""
        total = self.stats
        parts = [s.stats for s in self._made.values()]
        for key in ("expansions", "operator_applications", "backtracks", "goal_cuts"):
            setattr(total, key, sum(getattr(p, key) for p in parts))
        total.elapsed = time.perf_counter() - total.started
        total.timed_out = any(p.timed_out for p in parts)
        total.interrupted = any(p.interrupted for p in parts)
        # a bound ends the portfolio only when it stopped the last search left
        last = self._made[self.ended[-1]].stats.bound if len(self.ended) >= self.started else None
        total.bound = last
