"""The planner's plans as UP plans: a ``SequentialPlan`` of UP action
instances, or a ``HierarchicalPlan`` that adds the decomposition of every
task of the initial task network.

The planner's task tree (:mod:`htn.jshop.plans.tree`) gives, for each
compound task, the method that decomposed it (its branch label is the UP
method's name) and its subtasks in order, which are the UP method's subtasks
in the order :mod:`htn.up.convert` gave them. UP's ``MethodInstance`` also
wants the value of every method parameter, including those that only its
precondition binds: they are found again by replaying the plan from the
initial state and asking, in the state where the method was applied (before
its first action, in a total order), for a satisfier of its precondition that
gives its subtasks the arguments they have in the tree.
"""

from __future__ import annotations

from htn.jshop.language.terms import subst
from htn.jshop.logic.compile import head_unifier

from .convert import Conversion


def action_instances(conv: Conversion, plan) -> list:
    """The plan's steps as UP ``ActionInstance`` s, in order."""
    from unified_planning.plans import ActionInstance

    problem = conv.problem
    objects: dict = {}

    def obj(name):
        if name not in objects:
            objects[name] = problem.object(name)
        return objects[name]

    return [
        ActionInstance(problem.action(s.name[1:]), tuple(obj(a) for a in s.args))
        for s in plan.steps
    ]


def sequential_plan(conv: Conversion, plan):
    """The plan as a UP ``SequentialPlan``."""
    from unified_planning.plans import SequentialPlan

    return SequentialPlan(action_instances(conv, plan), conv.problem.environment)


def hierarchical_plan(conv: Conversion, plan):
    """The plan (recorded with its task tree) as a UP ``HierarchicalPlan``."""
    from unified_planning.plans import SequentialPlan
    from unified_planning.plans.hierarchical_plan import Decomposition, HierarchicalPlan

    actions = action_instances(conv, plan)
    flat = SequentialPlan(actions, conv.problem.environment)
    if plan.tree is None:
        raise ValueError("the plan has no task tree (plan with record_trees=True)")
    nodes = plan.tree.children
    if conv.instance.top is not None:  # the root task binding the network's variables
        nodes = nodes[0].children
    root = Decomposition({})
    _Rebuild(conv, actions).run(nodes, root)
    return HierarchicalPlan(flat, root)


class _Rebuild:
    """Builds the UP decomposition while replaying the plan (see the module docstring)."""

    def __init__(self, conv: Conversion, actions: list):
        from htn.jshop.search.planner import Planner

        self.conv = conv
        self.actions = actions
        self.replay = Planner.for_state(conv.domain, conv.instance.state)
        self.compiled: dict = {}
        em = conv.problem.environment.expression_manager
        self.objects = {o.name: em.ObjectExp(o) for o in conv.problem.all_objects}

    def run(self, nodes: list, root) -> None:
        from unified_planning.plans.hierarchical_plan import Decomposition, MethodInstance

        problem = self.conv.problem
        work = [(iter(zip(nodes, self.conv.network_order)), root.subtasks)]
        while work:
            it, sink = work[-1]
            item = next(it, None)
            if item is None:
                work.pop()
                continue
            node, subtask = item
            if node.step is not None:
                sink[subtask.identifier] = self.actions[node.step]
                if not self.replay.apply_step(node.name, tuple(node.args)):
                    raise RuntimeError(f"step {node.step + 1} of the plan does not replay")
                continue
            method = problem.method(node.branch)
            instance = MethodInstance(method, self.parameters(node, method), Decomposition({}))
            sink[subtask.identifier] = instance
            work.append(
                (
                    iter(zip(node.children, self.conv.method_order[method.name])),
                    instance.decomposition.subtasks,
                )
            )

    def parameters(self, node, method) -> tuple:
        """The values of the UP method's parameters in this decomposition."""
        m = self.conv.methods[method.name]
        branch = m.branches[0]
        key = id(m)
        if key not in self.compiled:
            self.compiled[key] = (
                head_unifier(m.head.args),
                self.replay.logic.precondition(branch.pre, m.head.args),
            )
        unify, sat = self.compiled[key]
        env = [None] * m.nvars
        if not unify(tuple(node.args), env):
            raise RuntimeError(f"{node.task} does not match method {method.name}")
        wanted = [(tuple(c.args), t.args) for c, t in zip(node.children, branch.tasks.items)]
        n = len(method.parameters)
        for nb in sat(env):
            if all(subst(t, nb) == args for args, t in wanted):
                return tuple(self.objects[v] for v in nb[:n])
        raise RuntimeError(f"no binding of method {method.name} gives {node.task} its subtasks")
