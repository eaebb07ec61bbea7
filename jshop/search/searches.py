"""The searches ``htn plan --search`` offers, by name (one table for the
command line and the library, as pyperplan keeps its searches).

* ``dfs`` -- JSHOP2's depth-first search in the written order
  (:mod:`htn.jshop.search.planner`): the default, and the only one for
  enumerating plans (``--all``) and for JSHOP2 input that cannot be
  grounded (:mod:`htn.jshop.search.jshop2_input`);
* ``gbfs`` -- greedy best-first progression search on the grounded problem
  with the relaxed composition heuristic (:mod:`htn.jshop.search.best_first`,
  :mod:`htn.jshop.search.heuristics`), cutting nodes that cannot reach
  the goal's chain in their order (:mod:`htn.jshop.search.goal_chain`);
* ``wastar`` -- the same as weighted A* (``g + 2 h``);
* ``auto`` -- ``dfs``, ``gbfs``, ``wastar`` (and, where the goal has a
  chain, GBFS with TDG_m) as a portfolio, interleaved in slices of CPU
  time (:mod:`htn.jshop.search.portfolio`).

Kept free of heavy imports: the command line reads the names for ``--help``.
"""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Plan

    from .stats import Stats


class Search(Protocol):
    """What every search is to its callers (``htn.api.plan``, the UP engine):
    ``plans(timeout)`` streams plans (the first is the answer of a search
    that is not enumerating), and ``stats`` says what it did, read once the
    stream has ended (``stats.loop_cuts``: reductions a loop check refused;
    0 for a search without one)."""

    stats: Stats

    # None only between slices of CPU time, where ``slice_s`` is set (the portfolio's turns)
    def plans(self, timeout: float | None = None) -> Generator[Plan | None, None, None]: ...


SEARCHES = {
    "dfs": "depth-first, JSHOP2's order",
    "gbfs": "greedy best-first, relaxed composition heuristic (grounded)",
    "wastar": "weighted A* (w = 2), same heuristic (grounded)",
    "auto": "dfs, gbfs and wastar interleaved, the first plan wins",
}


def _dfs(domain, instance, functions, **options) -> Search:
    from .planner import Planner

    return Planner(domain, instance, functions, **options)


def _best_first(weighted: bool) -> Callable[..., Search]:
    def make(domain, instance, functions, **options) -> Search:
        from .best_first import WASTAR_WEIGHT, BestFirst

        return BestFirst(
            domain,
            instance,
            weight=WASTAR_WEIGHT if weighted else None,
            label="wastar" if weighted else "gbfs",
            **options,
        )

    return make


def _auto(domain, instance, functions, **options) -> Search:
    from .portfolio import Portfolio

    return Portfolio(domain, instance, functions, **options)


# name -> a factory (domain, instance, functions, **options) -> Search; each
# imports its search when called, so that this table stays cheap to import
FACTORIES: dict = {
    "dfs": _dfs,
    "gbfs": _best_first(False),
    "wastar": _best_first(True),
    "auto": _auto,
}


def make_search(name: str, domain, instance, functions=None, **options) -> Search:
    """The search ``name`` (see :data:`SEARCHES`) for one problem instance."""
    factory = FACTORIES.get(name)
    if factory is None:
        raise ValueError(f"unknown search {name!r}; choose from {', '.join(SEARCHES)}")
    return factory(domain, instance, functions, **options)


def refusal(name: str, domain, all_plans: bool, problem=None, jshop2_compat: bool = False):
    """Why a search cannot run on this input, or None. A JSHOP2 domain is
    planned by the grounded searches where it can be grounded
    (:mod:`htn.jshop.search.jshop2_input`); ``auto`` then runs depth-first
    search alone where it cannot, ``gbfs`` and ``wastar`` refuse it."""
    if name == "dfs":
        return None
    if all_plans:
        return f"--search {name} finds plans one at a time; --all needs --search dfs"
    if domain.language == "hddl":
        return None
    if jshop2_compat:
        return "--jshop2-compat is JSHOP2 1.0.3's depth-first order; it needs --search dfs"
    if name == "auto" or problem is None:
        return None
    from .ground_formulas import NotGroundable
    from .jshop2_input import check

    try:
        for instance in problem.instances:
            check(domain, instance)
    except NotGroundable as e:
        return f"--search {name} plans JSHOP2 input it can ground; {e} (--search dfs plans it)"
    return None
