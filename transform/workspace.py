"""A plan being transformed (:class:`Workspace`: its top-level task list as
:class:`Unit` s, and the plan they give), and the names of the domain's
operators that the generic framework reads a plan by (:class:`Vocabulary`,
declared by a rule set: the built-in one's is
:data:`htn.transform.rules.KITCHEN`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.search.planner import Planner

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Plan
    from htn.jshop.plans.tree import TaskTree


@dataclass(frozen=True)
class Vocabulary:
    """The operators of a domain that the framework's facts and its static
    metric read a plan by, as a rule set declares them: ``handling``, those
    that take or put down an object, the arm being their last argument (a
    transport whose steps of these use one arm is ``one-arm``); ``navigate``,
    the one that moves the robot from an area to another, ``(navigate ?from
    ?to)`` (the ``navigation-static`` metric sums its distances)."""

    handling: frozenset
    navigate: str


@dataclass
class Unit:
    """One entry of the top-level task list: task atoms that replace one or
    more original top-level tasks (``paths``)."""

    tasks: list  # [S.TaskAtom]
    paths: list  # node paths of the original tasks it stands for
    transformed_by: str | None = None


@dataclass
class Workspace:
    """A plan being transformed: domain, problem instance, top-level units,
    and the plan and tree they currently give."""

    domain: S.Domain
    instance: S.ProblemInstance
    units: list
    plan: Plan | None = None  # set by from_problem: the plan with its tree
    log: list = field(default_factory=list)  # (rule, status, detail)
    frozen: set = field(default_factory=set)  # paths of rolled-back rewrites

    @classmethod
    def from_problem(cls, domain: S.Domain, instance: S.ProblemInstance) -> Workspace:
        plan = next(Planner(domain, instance, record_trees=True).plans(), None)
        if plan is None:
            raise HtnError.at(instance.pos, "the problem has no plan to transform")
        assert plan.tree is not None  # record_trees
        units = []
        for node, atom in zip(plan.tree.children, S.task_atoms(instance.tasks)):
            units.append(Unit([atom], [node.path]))
        return cls(domain, instance, units, plan)

    def task_list(self) -> S.TaskList:
        return S.TaskList([t for u in self.units for t in u.tasks])

    def annotated_tree(self) -> TaskTree:
        """The current plan's tree; each top-level node rewritten by a
        transformation carries the replacement tasks in its code-replacement
        slot (the paper's mechanism, here filled in for inspection)."""
        from htn.jshop.language.terms import source_atom

        assert self.plan is not None and self.plan.tree is not None  # see from_problem
        tree = self.plan.tree
        nodes = iter(tree.children)
        for unit in self.units:
            for node in [next(nodes) for _ in unit.tasks]:
                if unit.transformed_by:
                    node.code_replacement = [source_atom(t.name, t.args) for t in unit.tasks]
        return tree

    def replan(self, units: list[Unit] | None = None) -> Plan | None:
        """The first plan of ``units`` (default: the current ones), or None."""
        units = self.units if units is None else units
        tasks = S.TaskList([t for u in units for t in u.tasks])
        inst = S.ProblemInstance(self.instance.state, tasks, self.instance.pos)
        return next(Planner(self.domain, inst, record_trees=True).plans(timeout=30.0), None)

    def unit_of(self, path: str) -> Unit:
        for u in self.units:
            if path in u.paths:
                return u
        raise KeyError(path)
