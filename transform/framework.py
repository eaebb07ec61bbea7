"""The plan transformation framework (Kazhoyan et al., Table I), over task trees.

A plan's task tree is summarised as facts (:func:`tree_facts`), read by the
domain's operators that a rule set declares (a :class:`Vocabulary`; the
built-in rules' is :data:`htn.transform.rules.KITCHEN`); a
transformation is registered with an **applicability rule**: a query atom
answered, with the JSHOP2 axioms of a rules file, by this planner's own logic
engine (the paper uses Prolog). Each satisfier is an input schema for the
transformation function, which rewrites the plan's top-level task list
(:class:`Workspace`); unlike the paper's code replacements it may merge, move
or remove tasks. The rewritten task list is planned again with the domain, so
every transformed plan is checked against the domain's operators (each step's
precondition holds in sequence from the initial state); a transformation that
breaks the plan, or makes it costlier on the chosen metric, is rolled back with
the reason. Costs are re-projected: the mean of a metric over projected runs
of the plan (:func:`projected`), as the paper projects plans before executing
them.

API (as in the paper): :meth:`Framework.register_transformation`,
``disable_transformation``, ``enable_transformation``,
``prioritize_transformation``, ``apply_all_transformations``; the framework
with the built-in rules and the plugins' is
:func:`htn.transform.registered.default_framework`.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.logic.engine import Logic
from htn.jshop.logic.state import State
from htn.jshop.readers.load import parse_text

from .rules import KITCHEN, RULES_FILE
from .workspace import Unit, Vocabulary, Workspace

__all__ = [
    "Framework",
    "Transformation",
    "Unit",
    "Vocabulary",
    "Workspace",
    "METRICS",
    "RULES_FILE",
    "navigation_distance",
    "projected",
    "tree_facts",
]


# ------------------------------------------------------------------ facts


def tree_facts(ws: Workspace, vocabulary: Vocabulary = KITCHEN) -> list[tuple[str, tuple]]:
    """Facts about the current task list and its plan, for applicability rules.

    Tasks are named by the path they had in the original plan's tree (the
    current tree renumbers ``:call N`` as tasks are rewritten); the current
    tree's top-level nodes follow the task list one for one. A transport is
    ``one-arm`` when its steps of the ``vocabulary``'s handling operators name
    one arm.
    """
    containers = {a.args[0]: a.args[1] for a in ws.instance.state if a.pred == "container"}
    facts: list = [("tray-at", a.args[:2]) for a in ws.instance.state if a.pred == "tray"]
    plan = ws.plan
    assert plan is not None and plan.tree is not None  # see Workspace.from_problem
    nodes = iter(plan.tree.children)
    k = 0
    for unit in ws.units:
        unit_nodes = [next(nodes) for _ in unit.tasks]
        if (
            len(unit.tasks) != 1
            or unit.tasks[0].name != "transporting"
            or unit.paths[0] in ws.frozen
        ):
            facts.extend(("transformed", (p,)) for p in unit.paths)
            continue
        (atom,), (path,), (node,) = unit.tasks, unit.paths, unit_nodes
        obj, src, dst = atom.args
        k += 1
        facts.append(("transport", (path, obj, src, dst, float(k))))
        if src in containers:
            facts.append(("container-fetch", (path, src)))
            facts.append(("fetch-area", (path, containers[src])))
        else:
            facts.append(("fetch-area", (path, src)))
        facts.append(("deliver-area", (path, dst)))
        arms = set()
        for leaf in node.leaves():
            assert leaf.step is not None  # leaves() are the nodes with a step
            step = plan.steps[leaf.step]
            if step.name in vocabulary.handling:
                arms.add(step.args[-1])
        if len(arms) == 1:
            facts.append(("one-arm", (path,)))
    return facts


# ------------------------------------------------------------------ metrics


def navigation_distance(
    instance: S.ProblemInstance, plan, navigate: str = KITCHEN.navigate
) -> float:
    """Sum of straight-line distances of the plan's ``navigate`` steps (the
    operator of a vocabulary that moves the robot between two areas)."""
    from htn.robot.projection import world_from_atoms  # area coordinates, checked

    where = world_from_atoms([a for a in instance.state if a.pred == "area"]).places
    total = 0.0
    for s in plan.steps:
        if s.name == navigate and s.args[0] in where and s.args[1] in where:
            (x0, y0), (x1, y1) = where[s.args[0]], where[s.args[1]]
            total += math.hypot(x1 - x0, y1 - y0)
    return total


PROJECTION_SEEDS = range(64)


def projected(metric: str) -> Callable:
    """A cost: the mean of ``metric`` over projected runs of the plan on the
    projection robot, with the same seeds for every plan (a paired comparison,
    so the same plan always gets the same cost)."""

    def cost(ws: Workspace, plan) -> float:
        from htn.executor.config import load_retries

        from .projection import project

        retries = load_retries(ws.domain.file, ws.domain.operators)
        runs = [
            project(ws.domain, ws.instance, plan.steps, seed, retries=retries)
            for seed in PROJECTION_SEEDS
        ]
        return statistics.fmean(r[metric] for r in runs)

    return cost


# cost functions (workspace, plan) -> float used to roll back costlier rewrites
METRICS: dict[str, Callable] = {
    "navigation": projected("navigation"),
    "manipulation": projected("manipulation"),
    "actions": projected("actions"),
    "navigation-static": lambda ws, plan: navigation_distance(ws.instance, plan),
}


# ------------------------------------------------------------------ framework


@dataclass
class Transformation:
    name: str
    function: Callable  # (workspace, [schemas]) -> (description, paths) or None
    rule: str  # query atom, e.g. "(both-hands ?first ?second)"
    enabled: bool = True


class Framework:
    """Registered transformations, their priorities, and how to apply them."""

    def __init__(self, rules_file: Path = RULES_FILE, vocabulary: Vocabulary = KITCHEN):
        self.rules_text = Path(rules_file).read_text()
        self.vocabulary = vocabulary  # the operators its facts read the plan by
        self.transformations: list[Transformation] = []
        self.priorities: list[tuple[str, str]] = []  # (superior, inferior) names

    # -- the paper's API
    def register_transformation(
        self, function: Callable, applicability_rule: str, name: str | None = None
    ) -> Transformation:
        t = Transformation(
            name or function.__name__.replace("_", "-"), function, applicability_rule
        )
        self.transformations = [x for x in self.transformations if x.name != t.name] + [t]
        return t

    def _find(self, which) -> Transformation:
        for t in self.transformations:
            if t.name == which or t.function is which:
                return t
        raise HtnError(f"no transformation named {which!r} is registered")

    def disable_transformation(self, which) -> None:
        self._find(which).enabled = False

    def enable_transformation(self, which) -> None:
        self._find(which).enabled = True

    def prioritize_transformation(self, superior, inferior) -> None:
        """Make ``superior`` be tried before ``inferior``, keeping every earlier
        priority (the order is re-derived from all of them)."""
        sup, inf = self._find(superior), self._find(inferior)
        priorities = [(a, b) for a, b in self.priorities if (a, b) != (inf.name, sup.name)]
        priorities.append((sup.name, inf.name))
        order = list(self.transformations)
        for _ in range(len(order) ** 2 + 1):
            pos = {t.name: i for i, t in enumerate(order)}
            wrong = [(a, b) for a, b in priorities if a in pos and b in pos and pos[a] > pos[b]]
            if not wrong:
                self.priorities, self.transformations = priorities, order
                return
            a, b = wrong[0]
            moved = order.pop(pos[a])
            order.insert(pos[b], moved)
        raise HtnError(
            f"{sup.name} before {inf.name} contradicts the other priorities "
            f"{self.priorities}: they would form a cycle"
        )

    def apply_all_transformations(
        self,
        ws: Workspace,
        metric: str = "navigation",
        on_phase: Callable[[str], None] | None = None,
    ) -> Workspace:
        """Apply every enabled transformation, highest priority first, each as
        often as its rule finds untransformed tasks; keep only those that leave
        a valid plan that is not costlier on ``metric``. ``on_phase`` gets a
        few words as each rule is tried (progress for a caller)."""
        metric_cost = METRICS[metric]
        known: dict = {}  # id(plan) -> (plan, cost): each plan is projected once
        say = on_phase or (lambda text: None)

        def cost(ws, plan):
            if id(plan) not in known:
                known[id(plan)] = (plan, metric_cost(ws, plan))
            return known[id(plan)][1]

        for t in self.transformations:
            if not t.enabled:
                continue
            say(f"trying rule {t.name}")
            while True:
                schemas = self.query(ws, t.rule)
                if not schemas:
                    break
                before_units = list(ws.units)
                before_cost = cost(ws, ws.plan)
                result = t.function(ws, schemas)
                if not result:
                    ws.units = before_units
                    break
                described, paths = result
                plan = ws.replan()
                if plan is None:
                    ws.units = before_units
                    ws.frozen.update(paths)
                    ws.log.append(
                        (
                            t.name,
                            "rolled back",
                            f"{described}: the transformed task list has no valid plan",
                        )
                    )
                    continue
                after_cost = cost(ws, plan)
                if after_cost > before_cost + 1e-9:
                    ws.units = before_units
                    ws.frozen.update(paths)
                    ws.log.append(
                        (
                            t.name,
                            "rolled back",
                            f"{described}: {metric} {before_cost:g} -> {after_cost:g}",
                        )
                    )
                    continue
                ws.plan = plan
                ws.log.append(
                    (t.name, "applied", f"{described}: {metric} {before_cost:g} -> {after_cost:g}")
                )
        return ws

    def query(self, ws: Workspace, rule: str) -> list[dict]:
        """All satisfiers of ``rule`` over the workspace's facts, as dicts."""
        text = self.rules_text.rstrip().rstrip(")").rstrip().rstrip(")")
        domain = parse_text(f"{text}\n    (:method (query) {rule} ())\n  )\n)\n", "<rules>")
        (method,) = domain.methods["query"]
        names: dict = {}
        for v in _vars_of(method.branches[0].pre.expr):
            names.setdefault(v.name, v.index)
        state = State()
        for pred, args in tree_facts(ws, self.vocabulary):
            state.add(pred, args)
        logic = Logic(domain, state)
        sat = logic.precondition(method.branches[0].pre)
        out = []
        for env in sat([None] * method.nvars):
            out.append({name[1:]: env[i] for name, i in names.items()})
        return out


def _vars_of(expr) -> list:
    from htn.jshop.language.walk import walk_expr

    found: list = []
    walk_expr(expr, found.append)
    return found
