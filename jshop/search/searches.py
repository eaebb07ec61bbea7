"""The searches ``htn plan --search`` offers, by name (one table for the
command line and the library, as pyperplan keeps its searches).

* ``dfs`` -- JSHOP2's depth-first search in the written order
  (:mod:`htn.jshop.search.planner`): the default, and the only one for
  JSHOP2 input and for enumerating plans (``--all``);
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

SEARCHES = {
    "dfs": "depth-first, JSHOP2's order",
    "gbfs": "greedy best-first, relaxed composition heuristic (HDDL)",
    "wastar": "weighted A* (w = 2), same heuristic (HDDL)",
    "auto": "dfs, gbfs and wastar interleaved, the first plan wins (HDDL)",
}


def make_search(name: str, domain, instance, functions=None, **options):
    """A planner-like object for one problem instance: ``plans(timeout)``
    streams plans, ``stats`` says what the search did."""
    if name == "dfs":
        from .planner import Planner
        return Planner(domain, instance, functions, **options)
    if name in ("gbfs", "wastar"):
        from .best_first import WASTAR_WEIGHT, BestFirst
        return BestFirst(domain, instance, weight=WASTAR_WEIGHT if name == "wastar" else None,
                         label=name, **options)
    if name == "auto":
        from .portfolio import Portfolio
        return Portfolio(domain, instance, functions, **options)
    raise ValueError(f"unknown search {name!r}; choose from {', '.join(SEARCHES)}")


def refusal(name: str, domain, all_plans: bool):
    """Why a search cannot run on this input, or None."""
    if name == "dfs":
        return None
    if all_plans:
        return f"--search {name} finds plans one at a time; --all needs --search dfs"
    if domain.language != "hddl":
        return (f"--search {name} reads HDDL; JSHOP2 domains are planned depth-first "
                "under the manual's semantics (--search dfs)")
    return None
