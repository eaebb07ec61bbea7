"""A JSHOP2-compatible HTN planner: read domains and problems, find plans.

Typical use::

    from jshop import load_domain, load_problem, Planner
    domain = load_domain("domains/domestic.jshop")
    problem = load_problem("problems/bring_object.jshop")
    planner = Planner(domain, problem.instances[0])
    plan = next(planner.plans())
"""
from .errors import HtnError, PlanningError
from .functions import FunctionTable
from .parser import load_domain, load_problem, parse_text
from .plan import Plan, Step
from .planner import Planner
from .tree import TaskTree

__all__ = ["HtnError", "PlanningError", "FunctionTable", "load_domain", "load_problem",
           "parse_text", "Plan", "Step", "Planner", "TaskTree"]
