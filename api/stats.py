"""Planning statistics for a scenario, as in Table 1 of the planning paper.

For one domain and problem: how many plans the planner returns (and how many
distinct action sequences), how long finding all of them takes, the shortest
plan's length, and the size of the domain (methods and operators).
"""
from __future__ import annotations

import statistics
import time
from dataclasses import asdict, dataclass
from typing import Optional

from htn.jshop.readers.load import load_domain, load_problem
from htn.jshop.search.planner import Planner

# Table 1 of Shpieva & Awaad: the paper's own figures for its two scenarios.
PAPER = {
    "bring_object": {"plans": 3, "distinct_plans": 1, "plan_s": 3.0, "min_length": 8,
                     "methods": 13, "operators": 7},
    "guide_robot": {"plans": 1, "distinct_plans": 1, "plan_s": 1.5, "min_length": 5,
                    "methods": 13, "operators": 7},
}


@dataclass
class ScenarioStats:
    domain: str
    problem: str
    plans: int
    distinct_plans: int
    plan_ms: float
    min_length: Optional[int]
    methods: int
    operators: int
    timed_out: bool = False

    def as_dict(self) -> dict:
        return asdict(self)


def scenario_stats(domain_path: str, problem_path: str, functions=None, repeat: int = 1,
                   timeout: Optional[float] = None) -> ScenarioStats:
    """Enumerate every plan ``repeat`` times; report the median wall time."""
    domain = load_domain(domain_path, functions)
    problem = load_problem(problem_path, functions)
    times = []
    plans: list = []
    timed_out = False
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        plans = []
        for inst in problem.instances:
            planner = Planner(domain, inst, functions)
            plans.extend(tuple(p.lines()) for p in planner.plans(timeout))
            timed_out = timed_out or planner.stats.timed_out
        times.append(time.perf_counter() - t0)
    return ScenarioStats(
        domain=domain_path, problem=problem_path, plans=len(plans),
        distinct_plans=len(set(plans)), plan_ms=round(statistics.median(times) * 1000, 3),
        min_length=min((len(p) for p in plans), default=None),
        methods=domain.n_methods, operators=domain.n_operators, timed_out=timed_out)
