"""htn as an engine of unified-planning (UP, the AIPlan4EU framework).

Importing this module registers the engine ``htn`` with the factory of UP's
global environment, so that afterwards::

    import htn.up
    from unified_planning.shortcuts import OneshotPlanner
    with OneshotPlanner(name="htn") as planner:
        result = planner.solve(problem)        # a HierarchicalProblem

works, and ``PlanValidator(name="htn")`` validates hierarchical plans. UP 1.3
discovers engines outside its own list only through ``Factory.add_engine``
(what :func:`register` calls) or an ``up.ini`` file; see docs/up.md for the
file. Needs the ``up`` extra (``pip install 'htn[up]'``); ``import htn``
does not import this module.

The engine is :class:`htn.up.engine.HtnEngine`; its problem kind is in
:mod:`htn.up.kind`, the conversion of UP problems in :mod:`htn.up.convert`.
"""

from __future__ import annotations

ENGINE = ("htn.up.engine", "HtnEngine")  # module and class, as UP's factory takes them


def register(environment=None, name: str = "htn") -> None:
    """Add the engine to the factory of ``environment`` (UP's global one by
    default) under ``name``, unless an engine of that name is there already
    (an ``up.ini`` may have registered it)."""
    from unified_planning.environment import get_environment

    factory = get_environment(environment).factory
    if name not in factory.engines:
        factory.add_engine(name, *ENGINE)


register()
