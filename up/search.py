"""One ``solve`` of the ``htn`` engine: run the planner on a converted
problem and say what came of it in UP's terms (see :mod:`htn.up.engine` for
the statuses and options)."""

from __future__ import annotations

import time
from typing import IO

from unified_planning.engines import LogLevel, LogMessage, PlanGenerationResult
from unified_planning.engines import PlanGenerationResultStatus as Status

from htn.jshop.search.ground_formulas import NotGroundable
from htn.jshop.search.limits import MemoryLimit
from htn.jshop.search.searches import make_search
from htn.jshop.search.stream import SearchStream

from .convert import Conversion
from .decompose import hierarchical_plan, sequential_plan


def search(
    engine,
    conv: Conversion,
    options: dict,
    started: float,
    timeout: float | None,
    output_stream: IO[str] | None,
    logs: list,
) -> PlanGenerationResult:
    """Plan for ``conv`` within ``timeout`` seconds of ``started``."""
    hierarchical = options["plan_kind"] == "hierarchical"
    max_memory = options["max_memory"]
    planner = make_search(
        options["search"],
        conv.domain,
        conv.instance,
        record_trees=hierarchical,
        tree_paths=False,
        max_depth=options["max_depth"],
        loop_check=options["loop_check"],
        max_memory=max_memory << 20 if max_memory else None,
    )
    converted = time.perf_counter()
    plans = SearchStream(
        [conv.instance],
        lambda k, instance: planner,
        started=started,
        timeout=timeout,
        limit=None if options["optimize"] else 1,
    )
    best, found = None, 0
    try:
        for plan in plans:  # the cheapest plan, and a line for each
            found += 1
            if best is None or plan.cost < best.cost:
                best = plan
            if output_stream is not None:
                output_stream.write(f"htn: plan {found}: {len(plan)} actions, cost {plan.cost:g}\n")
    except NotGroundable as e:  # gbfs, wastar: the problem cannot be grounded
        logs.append(LogMessage(LogLevel.ERROR, f"htn: search {options['search']}: {e}"))
        return PlanGenerationResult(
            Status.UNSUPPORTED_PROBLEM, None, engine.name, log_messages=logs
        )
    finally:
        plans.close()
    stats = planner.stats
    timed_out = plans.stats["timed_out"]
    cut = stats.loop_cuts
    complete = (
        not timed_out and stats.bound is None and cut == 0 and (options["optimize"] or best is None)
    )
    status = _status(best, timed_out, complete, stats.bound, options["optimize"])
    logs.append(LogMessage(LogLevel.INFO, _summary(found, best, stats, cut, timed_out)))
    if stats.bound is not None:
        logs.append(LogMessage(LogLevel.WARNING, str(stats.bound)))
    up_plan = None
    if best is not None:
        up_plan = hierarchical_plan(conv, best) if hierarchical else sequential_plan(conv, best)
    total = time.perf_counter() - started
    metrics = {
        "engine_internal_time": str(total),
        "conversion_time": str(converted - started),
        "search_time": str(stats.elapsed),
        "plans_found": str(found),
        "expansions": str(stats.expansions),
        "backtracks": str(stats.backtracks),
    }
    if output_stream is not None:
        output_stream.write(f"htn: {status.name} after {total:.3f} s\n")
    return PlanGenerationResult(status, up_plan, engine.name, metrics=metrics, log_messages=logs)


def _status(best, timed_out: bool, complete: bool, bound, optimize: bool) -> Status:
    if timed_out:
        return Status.TIMEOUT
    if best is not None:
        return Status.SOLVED_OPTIMALLY if optimize and complete else Status.SOLVED_SATISFICING
    if isinstance(bound, MemoryLimit):
        return Status.MEMOUT
    return Status.UNSOLVABLE_PROVEN if complete else Status.UNSOLVABLE_INCOMPLETELY


def _summary(found: int, best, stats, cut: int, timed_out: bool) -> str:
    what = (
        f"{found} plan(s) found, the best with {len(best)} actions and cost {best.cost:g}"
        if best is not None
        else "no plan found"
    )
    how = (
        f"{stats.elapsed:.3f} s of search, {stats.expansions:,} expansions, "
        f"{stats.backtracks:,} backtracks"
    )
    if cut:
        how += f", {cut:,} reductions cut by the loop check"
    if timed_out:
        how += ", stopped at the time limit"
    return f"htn: {what} ({how})"
