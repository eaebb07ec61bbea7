"""The plans of a problem's instances, searched one after another within one
time limit, their searches' statistics summed: the loop under ``htn plan``
(:class:`htn.api.plan.PlanStream`) and the UP engine's ``solve``
(:mod:`htn.up.search`), kept once here."""

from __future__ import annotations

import time
from collections.abc import Callable, Generator, Iterator
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Plan

    from .searches import Search


def new_stats() -> dict:
    """The statistics of a search over a problem's instances, before it starts
    (their keys are those of ``htn plan -f json``'s statistics line)."""
    return {
        "plans_found": 0,
        "search_ms": 0.0,
        "expansions": 0,
        "operator_applications": 0,
        "backtracks": 0,
        "timed_out": False,
        "interrupted": False,
        "depth_limit_reached": False,
        "memory_limit_reached": False,
        "shortest_plan": None,
    }


class SearchStream:
    """The plans of ``instances`` in order, streamed by iterating (once): for
    each instance ``make(k, instance)`` gives its search (a
    :class:`~htn.jshop.search.searches.Search`), which runs for what is left
    of ``timeout`` seconds from ``started`` (``time.perf_counter()``) and
    yields at most ``limit`` plans (None: every one). Each plan gets
    ``instance`` (``k``). The stream ends at the time limit or at the first
    bound (``max_depth``, ``max_memory``) reached.

    ``stats``: the summed statistics so far (final once the stream ends or
    is closed); ``bound``: the bound that stopped a search (a
    :class:`~htn.jshop.search.limits.SearchBound`), if one did.
    """

    def __init__(
        self,
        instances,
        make: Callable[[int, object], Search],
        *,
        started: float,
        timeout: float | None,
        limit: int | None,
    ):
        self.instances, self.make = instances, make
        self.started, self.timeout, self.limit = started, timeout, limit
        self.stats = new_stats()
        self.bound = None
        self._plans = self._search()

    def __iter__(self) -> Iterator[Plan]:
        return self._plans

    def __next__(self) -> Plan:
        return next(self._plans)

    def close(self) -> None:
        """End the search now (its statistics are then final)."""
        self._plans.close()

    def __enter__(self) -> SearchStream:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _search(self) -> Generator[Plan, None, None]:
        stats = self.stats
        try:
            for k, inst in enumerate(self.instances):
                remaining = None
                if self.timeout is not None:
                    remaining = self.timeout - (time.perf_counter() - self.started)
                    if remaining <= 0:
                        stats["timed_out"] = True
                        break
                planner = self.make(k, inst)
                found = planner.plans(remaining)
                try:
                    for p in found:
                        assert p is not None  # slice_s is not set: the search never pauses
                        p.instance = k  # the problem instance's index (not a field)
                        stats["plans_found"] += 1
                        if stats["shortest_plan"] is None or len(p.steps) < stats["shortest_plan"]:
                            stats["shortest_plan"] = len(p.steps)
                        yield p
                        if self.limit is not None and planner.stats.plans_found >= self.limit:
                            break
                finally:
                    found.close()
                    _add(stats, planner.stats.as_dict())
                if planner.stats.timed_out:
                    stats["timed_out"] = True
                    break
                if planner.stats.bound is not None:
                    reached = planner.stats.as_dict()
                    for key in ("depth_limit_reached", "memory_limit_reached"):
                        stats[key] = reached[key]
                    self.bound = planner.stats.bound
                    break
        except KeyboardInterrupt:
            stats["interrupted"] = True
            raise
        finally:
            stats["search_ms"] = round(stats["search_ms"], 3)


def _add(totals: dict, s: dict) -> None:
    for key in ("expansions", "operator_applications", "backtracks"):
        totals[key] += s[key]
    totals["search_ms"] += s["search_ms"]
    if "found_by" in s:  # --search auto: which search found the plans
        totals["found_by"] = s["found_by"]
    if "loop_cuts" in s:
        totals["loop_cuts"] = totals.get("loop_cuts", 0) + s["loop_cuts"]
