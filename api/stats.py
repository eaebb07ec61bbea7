"""The stats use case: planning statistics for scenarios, as in Table 1 of
the planning paper (``htn stats``).

For one domain and problem: how many plans the planner returns (and how many
distinct action sequences), how long finding all of them takes, the shortest
plan's length, and the size of the domain (methods and operators).
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Iterable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from htn.installation import EXAMPLES
from htn.jshop.language.errors import HtnError
from htn.jshop.search.planner import Planner

from .inputs import function_table, read_inputs

if TYPE_CHECKING:
    from htn.jshop.language.functions import Guard

    from .inputs import FunctionsInput, StrPath

# the paper's two scenarios, as bundled examples
SCENARIOS = [
    ("domains/domestic.jshop", "problems/bring_object.jshop"),
    ("domains/domestic.jshop", "problems/guide_robot.jshop"),
]

# Table 1 of Shpieva & Awaad: the paper's own figures for its two scenarios.
PAPER = {
    "bring_object": {
        "plans": 3,
        "distinct_plans": 1,
        "plan_s": 3.0,
        "min_length": 8,
        "methods": 13,
        "operators": 7,
    },
    "guide_robot": {
        "plans": 1,
        "distinct_plans": 1,
        "plan_s": 1.5,
        "min_length": 5,
        "methods": 13,
        "operators": 7,
    },
}


@dataclass
class ScenarioStats:
    domain: str
    problem: str
    plans: int
    distinct_plans: int
    plan_ms: float
    min_length: int | None
    methods: int
    operators: int
    timed_out: bool = False
    repeats: int = 1  # enumerations timed (fewer than asked when time ran out)
    # the located warnings of the inputs' check (as htn.plan has them)
    warnings: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        """The figures (``htn stats --json``), without the warnings."""
        out = asdict(self)
        del out["warnings"]
        return out


def bundled_file(rel: str) -> str:
    """A bundled example (``domains/...``, ``problems/...``), shown relative
    to the current folder when it lies below it."""
    path = EXAMPLES / rel
    if not path.is_file():
        raise HtnError(f"the bundled example {rel} is missing from this installation", str(path))
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def scenarios(files: Iterable[StrPath] = ()) -> list[tuple[str, str]]:
    """The (domain, problem) pairs of ``files``: a DOMAIN and then PROBLEMs in
    it; without files, the paper's two scenarios (bring an object, guide a
    robot; the bundled examples)."""
    paths = [os.fspath(f) for f in files]
    if len(paths) == 1:
        raise HtnError("give a domain and at least one problem (or no files)")
    if not paths:
        return [(bundled_file(d), bundled_file(p)) for d, p in SCENARIOS]
    return [(paths[0], p) for p in paths[1:]]


def stats(
    files: Iterable[StrPath] = (),
    *,
    repeat: int = 1,
    functions: FunctionsInput = None,
    timeout: float | None = None,
    stops: Guard | None = None,
) -> list[ScenarioStats]:
    """The statistics of each scenario of ``files`` (see :func:`scenarios`):
    every plan enumerated ``repeat`` times, the median time reported.
    ``timeout`` bounds the whole call (checked between expansions): an
    enumeration it cuts short is partial (``timed_out``), and no repeat
    starts after it."""
    until = None if timeout is None else time.perf_counter() + timeout
    table = function_table(functions, stops)
    return [scenario_stats(d, p, table, repeat, until=until) for d, p in scenarios(files)]


def scenario_stats(
    domain_path: str,
    problem_path: str,
    functions: FunctionsInput = None,
    repeat: int = 1,
    *,
    until: float | None = None,
) -> ScenarioStats:
    """Enumerate every plan ``repeat`` times; report the median wall time.
    ``until`` (a ``time.perf_counter()`` value) bounds all of them: an
    enumeration cut short is the last."""
    table = function_table(functions)
    inputs = read_inputs(domain_path, problem_path, table)
    domain, problem = inputs.domain, inputs.problem
    times: list[float] = []
    plans: list[tuple[str, ...]] = []
    timed_out = False
    for _ in range(max(1, repeat)):
        t0 = time.perf_counter()
        plans = []
        for inst in problem.instances:
            # what is left of the time (at least a moment: the planner then stops at once)
            budget = None if until is None else max(until - time.perf_counter(), 1e-6)
            planner = Planner(domain, inst, table)
            # (None would mark a slice of CPU time: no slices are asked for here)
            plans.extend(tuple(p.lines()) for p in planner.plans(budget) if p is not None)
            timed_out = timed_out or planner.stats.timed_out
        times.append(time.perf_counter() - t0)
        if timed_out or until is not None and time.perf_counter() >= until:
            break  # a partial enumeration says nothing more if repeated
    return ScenarioStats(
        domain=domain_path,
        problem=problem_path,
        plans=len(plans),
        distinct_plans=len(set(plans)),
        plan_ms=round(statistics.median(times) * 1000, 3),
        min_length=min((len(p) for p in plans), default=None),
        methods=domain.n_methods,
        operators=domain.n_operators,
        timed_out=timed_out,
        repeats=len(times),
        warnings=inputs.warnings,
    )
