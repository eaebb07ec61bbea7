"""What a search did: plans found, expansions, operator applications,
backtracks, time, what ended it early (``--timeout``, Ctrl-C, a bound), and
in a portfolio which search found the plans, and how many reductions the
loop check refused (a search that ends with none found a "no plan" it can
stand by; with some, a plan that revisits a state may have been cut)."""

from __future__ import annotations

from .limits import DepthLimit, MemoryLimit


class Stats:
    __slots__ = (
        "plans_found",
        "expansions",
        "operator_applications",
        "backtracks",
        "started",
        "elapsed",
        "timed_out",
        "interrupted",
        "bound",
        "found_by",
        "loop_cuts",
        "goal_cuts",
    )

    def __init__(self):
        self.plans_found = 0
        self.expansions = 0
        self.operator_applications = 0
        self.backtracks = 0
        self.started = 0.0
        self.elapsed = 0.0
        self.timed_out = False
        self.interrupted = False
        self.bound = None  # the SearchBound (depth or memory) that stopped the search
        self.found_by = None  # which search of a portfolio found the plans (--search auto)
        self.loop_cuts = 0  # reductions the loop check refused (loops.py): 0 = complete
        self.goal_cuts = 0  # nodes the goal-chain cut dropped (goal_chain.py): sound

    def as_dict(self) -> dict:
        out = {
            "plans_found": self.plans_found,
            "search_ms": round(self.elapsed * 1000, 3),
            "expansions": self.expansions,
            "operator_applications": self.operator_applications,
            "backtracks": self.backtracks,
            "timed_out": self.timed_out,
            "interrupted": self.interrupted,
            "depth_limit_reached": isinstance(self.bound, DepthLimit),
            "memory_limit_reached": isinstance(self.bound, MemoryLimit),
        }
        if self.found_by is not None:
            out["found_by"] = self.found_by
        if self.loop_cuts:
            out["loop_cuts"] = self.loop_cuts
        if self.goal_cuts:
            out["goal_cuts"] = self.goal_cuts
        return out
