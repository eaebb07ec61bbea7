"""The ``htn`` engine of unified-planning: a oneshot planner and a plan validator.

It solves UP hierarchical problems of the kind :mod:`htn.up.kind` declares
with the search its ``search`` option names (JSHOP2's depth-first search,
manual sections 4 and 5.2.3, under HDDL's semantics by default; greedy
best-first or weighted A* on the grounded problem; or all of them as a
portfolio), after converting the problem in memory (:mod:`htn.up.convert`),
and validates hierarchical plans (:mod:`htn.up.check`).

Options (UP's ``params``: ``OneshotPlanner(name="htn", params={...})``):

``max_depth`` (int, default 250,000)
    nested method reductions without an action before the search stops
    (``htn plan --max-depth``);
``max_memory`` (int, MB)
    resident memory at which the search stops (``--max-memory``; default 80%
    of what is available);
``loop_check`` (bool, default True)
    refuse to reduce a task again in the same state while an identical one is
    being reduced (:mod:`htn.jshop.search.loops`): recursive domains then
    terminate, at the price of completeness;
``optimize`` (bool, default False)
    go on after the first plan and return the cheapest (the problem's action
    costs; 1 per action otherwise): ``SOLVED_OPTIMALLY`` when the search space
    was exhausted with no bound reached and no loop cut, otherwise the best
    found (``SOLVED_SATISFICING``, or ``TIMEOUT`` at the time limit);
``search`` (``"dfs"``, ``"gbfs"``, ``"wastar"`` or ``"auto"``, default dfs)
    the search of ``htn plan --search``: depth-first in JSHOP2's order, or
    the heuristic progression searches on the grounded problem (greedy
    best-first, weighted A*) and the portfolio of all of them. With a
    heuristic search, ``max_depth`` and ``loop_check`` concern only the
    depth-first part, and "no plan" is ``UNSOLVABLE_PROVEN`` (the grounded
    space was exhausted);
``plan_kind`` (``"hierarchical"`` or ``"sequential"``, default hierarchical)
    a ``HierarchicalPlan`` (the actions and the decomposition of every task),
    or only its ``SequentialPlan`` (cheaper: no task tree is recorded).
    A hierarchical plan also gives its sequential plan with
    ``plan.convert_to(PlanKind.SEQUENTIAL_PLAN, problem)``.

Results follow UP's conventions: ``SOLVED_SATISFICING`` with the first plan
(JSHOP2's order); ``UNSOLVABLE_PROVEN`` when the whole search space was
explored (no bound reached, no loop cut); ``UNSOLVABLE_INCOMPLETELY`` when it
was explored within a bound or with loops cut; ``TIMEOUT`` (with the best plan
found, if any) at ``timeout`` seconds (wall clock, conversion included);
``MEMOUT`` at the memory bound; ``UNSUPPORTED_PROBLEM`` for what the
conversion cannot express (with ``skip_checks``). Log messages say what
happened in one line each; ``metrics`` has ``engine_internal_time``.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable
from typing import IO

from unified_planning.engines import (
    Credits,
    Engine,
    LogLevel,
    LogMessage,
    PlanGenerationResult,
    ValidationResult,
    ValidationResultStatus,
)
from unified_planning.engines import PlanGenerationResultStatus as Status
from unified_planning.engines.mixins import OneshotPlannerMixin, PlanValidatorMixin
from unified_planning.engines.mixins.oneshot_planner import OptimalityGuarantee
from unified_planning.engines.results import FailedValidationReason
from unified_planning.exceptions import UPUsageError
from unified_planning.plans import PlanKind

from htn.jshop.logic.caches import clear_caches
from htn.jshop.search.limits import DEFAULT_MAX_DEPTH
from htn.jshop.search.searches import SEARCHES

from . import kind
from .convert import checked
from .formulas import Unsupported

OPTIONS = {
    # name: (type, default)
    "max_depth": (int, DEFAULT_MAX_DEPTH),
    "max_memory": (int, None),
    "loop_check": (bool, True),
    "optimize": (bool, False),
    "plan_kind": (str, "hierarchical"),
    "search": (str, "dfs"),
}
PLAN_KINDS = ("hierarchical", "sequential")

CREDITS = Credits(
    name="htn",
    author="the htn developers",
    contact="the htn project (see its README.md)",
    website="the htn project's documentation, docs/up.md",
    license="MIT",
    short_description="htn: a JSHOP2-compatible HTN planner that reads HDDL, with "
    "depth-first and heuristic searches.",
    long_description="htn plans with JSHOP2's depth-first decomposition under HDDL's "
    "semantics (type predicates, precondition pull-up, loop check), or with "
    "greedy best-first or weighted A* search on the grounded problem (the "
    "relaxed composition heuristic), or a portfolio of them (the 'search' "
    "option), and returns hierarchical plans.",
)


def parse_options(options: dict) -> dict:
    """The engine's options with defaults; a one-line ``UPUsageError`` for
    an unknown name or a value of the wrong type."""
    out = {name: default for name, (_, default) in OPTIONS.items()}
    for name, value in options.items():
        if name not in OPTIONS:
            raise UPUsageError(f"htn has no option {name!r}; its options are {', '.join(OPTIONS)}")
        wanted = OPTIONS[name][0]
        if wanted is int and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise UPUsageError(f"htn option {name} must be a positive integer, not {value!r}")
        if wanted is not int and not isinstance(value, wanted):
            raise UPUsageError(f"htn option {name} must be a {wanted.__name__}, not {value!r}")
        out[name] = value
    if out["search"] not in SEARCHES:
        raise UPUsageError(
            f"htn option search must be one of {', '.join(SEARCHES)}, not {out['search']!r}"
        )
    if out["plan_kind"] not in PLAN_KINDS:
        raise UPUsageError(
            f"htn option plan_kind must be one of {', '.join(PLAN_KINDS)}, not {out['plan_kind']!r}"
        )
    return out


class HtnEngine(Engine, OneshotPlannerMixin, PlanValidatorMixin):
    """htn through unified-planning (see the module docstring)."""

    def __init__(self, **options):
        Engine.__init__(self)
        OneshotPlannerMixin.__init__(self)
        self.options = parse_options(options)

    @property
    def name(self) -> str:
        return "htn"

    @staticmethod
    def supported_kind():
        return kind.supported_kind()

    @staticmethod
    def supports(problem_kind) -> bool:
        return problem_kind <= kind.supported_kind()

    @staticmethod
    def supports_plan(plan_kind) -> bool:
        return plan_kind == PlanKind.HIERARCHICAL_PLAN

    @staticmethod
    def satisfies(optimality_guarantee) -> bool:
        return optimality_guarantee == OptimalityGuarantee.SATISFICING

    @staticmethod
    def get_credits(**kwargs) -> Credits | None:
        return CREDITS

    # ------------------------------------------------------------ planning
    def _solve(
        self,
        problem,
        heuristic: Callable | None = None,
        timeout: float | None = None,
        output_stream: IO[str] | None = None,
    ) -> PlanGenerationResult:
        from .search import search

        started = time.perf_counter()
        logs: list = []
        if heuristic is not None:
            warnings.warn(
                "htn does not use a heuristic given by the caller: its searches "
                "use their own (the 'search' option)",
                stacklevel=2,
            )
            logs.append(LogMessage(LogLevel.WARNING, "heuristic ignored"))
        try:
            conv = checked(problem)
        except Unsupported as e:
            extra = kind.unsupported_features(problem.kind)
            logs.append(
                LogMessage(
                    LogLevel.ERROR,
                    f"unsupported problem: {e}"
                    + (f" (features htn does not support: {', '.join(extra)})" if extra else ""),
                )
            )
            return PlanGenerationResult(
                Status.UNSUPPORTED_PROBLEM, None, self.name, log_messages=logs
            )
        logs += [LogMessage(LogLevel.WARNING, w) for w in conv.warnings]
        try:
            return search(self, conv, self.options, started, timeout, output_stream, logs)
        finally:
            # every problem is a new domain (converted anew): what was compiled
            # for this one is never used again
            clear_caches()

    # ------------------------------------------------------------ validation
    def _validate(self, problem, plan) -> ValidationResult:
        from unified_planning.plans import HierarchicalPlan

        from .check import check

        started = time.perf_counter()
        if not isinstance(plan, HierarchicalPlan):
            return self._unknown(f"htn validates hierarchical plans, not {plan.kind.name}")
        try:
            conv = checked(problem)
            verdict = check(conv, plan)
        except Unsupported as e:
            return self._unknown(f"unsupported problem: {e}")
        finally:
            clear_caches()
        metrics = {"engine_internal_time": str(time.perf_counter() - started)}
        if verdict.valid:
            return ValidationResult(
                ValidationResultStatus.VALID,
                self.name,
                [],
                metric_evaluations=_metric_values(problem, plan),
                metrics=metrics,
            )
        reason = None
        if verdict.failed_action is not None:
            reason = FailedValidationReason.INAPPLICABLE_ACTION
        elif verdict.goal_failed:
            reason = FailedValidationReason.UNSATISFIED_GOALS
        return ValidationResult(
            ValidationResultStatus.INVALID,
            self.name,
            [LogMessage(LogLevel.INFO, verdict.message)],
            reason=reason,
            inapplicable_action=verdict.failed_action,
            metrics=metrics,
        )

    def _unknown(self, message: str) -> ValidationResult:
        return ValidationResult(
            ValidationResultStatus.UNKNOWN, self.name, [LogMessage(LogLevel.ERROR, message)]
        )


def _metric_values(problem, plan) -> dict | None:
    """The value of each of the problem's quality metrics for a valid plan."""
    out = {}
    actions = plan.action_plan.actions
    for metric in problem.quality_metrics:
        if metric.is_minimize_sequential_plan_length():
            out[metric] = len(actions)
        elif metric.is_minimize_action_costs():
            total = 0
            for a in actions:
                cost = metric.get_action_cost(a.action)
                total += cost.constant_value() if cost is not None else 1
            out[metric] = total
    return out or None


__all__ = ["HtnEngine", "OPTIONS", "parse_options"]
