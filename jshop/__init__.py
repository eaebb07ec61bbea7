"""A JSHOP2-compatible HTN planner: read domains and problems, find plans.

Typical use::

    from htn.jshop import load_domain, load_problem, Planner
    domain = load_domain("domains/domestic.jshop")
    problem = load_problem("problems/bring_object.jshop")
    planner = Planner(domain, problem.instances[0])
    plan = next(planner.plans())

Its rooms: :mod:`.language` (terms, syntax, functions, errors), :mod:`.readers`
(JSHOP2 and HDDL files), :mod:`.logic` (the logic engine and its generated
code), :mod:`.search` (the planner) and :mod:`.plans` (plans, task trees,
plan files, validation, ``--explain``). The names below are imported on first
use, so that importing ``htn.jshop.language.errors`` (as the command line
does for ``htn --help``) does not load the parser.
"""

from importlib import import_module

_EXPORTS = {
    "HtnError": "language.errors",
    "PlanningError": "language.errors",
    "FunctionTable": "language.functions",
    "load_domain": "readers.load",
    "load_problem": "readers.load",
    "load_inputs": "readers.load",
    "parse_text": "readers.load",
    "Plan": "plans.plan",
    "Step": "plans.plan",
    "TaskTree": "plans.tree",
    "Planner": "search.planner",
}

__all__ = list(_EXPORTS)


def __getattr__(name):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'jshop' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value
