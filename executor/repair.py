"""Repair in the task tree: re-plan the smallest enclosing task that can be
re-planned from what the robot observes, and graft it into the behaviour tree.

(Before re-planning, the task dispatcher tries the failed step itself again
when its retry limit allows and :func:`retry_applies`.)

When an action ends failed or aborted, the tasks that enclose it are tried
from the nearest up: each is planned again (JSHOP2's search, this planner's
:class:`~htn.jshop.search.planner.Planner`, on that one task atom) from the
**observed state**: the problem's static facts plus what the robot observes of
the domain's dynamic predicates. A plan is accepted when what comes after the
task in the current plan still applies after it (each remaining step's
precondition holds in sequence); the task's subtree in the behaviour tree is
then replaced by the new one, and what is done and what comes after stays as
it is. At the root, the pending top-level tasks are planned together (or,
when the plan's task tree is unknown, the problem's tasks). If no enclosing
task has a plan, there is no repair and the robot holds its pose.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from py_trees.behaviour import Behaviour
from py_trees.composites import Composite

from htn.jshop.language import syntax as S
from htn.jshop.search.planner import Planner

from .task_bt import (
    ROOT_NAME,
    MakeAction,
    action_of,
    actions,
    build,
    enclosing_tasks,
    label_among,
    rebase,
    task_atom,
    task_node,
    task_of,
)

if TYPE_CHECKING:
    from htn.jshop.language.functions import FunctionTable
    from htn.jshop.plans.plan import Plan, Step
    from htn.robot.interface import Robot

    from .behaviours import ActionContext

PLAN_TIMEOUT = 10.0  # seconds of search per candidate task


@dataclass
class Repair:
    """A repair found: the task replaced (node path), its new plan, and the
    behaviours it replaces."""

    path: str  # the node path of the (first) task re-planned
    tasks: list[str]
    plan: Plan
    target: Behaviour  # the sequence repaired (the root for the root)
    replaced: list[Behaviour] = field(default_factory=list)

    @property
    def paths(self) -> list[str]:
        """Node paths of every task replaced."""
        return [task_node(b).path for b in self.replaced]


def observed_instance(
    domain: S.Domain,
    instance: S.ProblemInstance,
    robot: Robot,
    tasks: S.TaskList | None = None,
) -> S.ProblemInstance:
    """The current state as the robot observes it: static facts of the
    problem plus the observed facts of the domain's dynamic predicates."""
    dynamic = domain.dynamic_predicates()
    atoms = [a for a in instance.state if a.pred not in dynamic]
    atoms += [S.Atom(pred, tuple(args)) for pred, args in robot.observe()]
    return S.ProblemInstance(atoms, tasks if tasks is not None else instance.tasks, instance.pos)


def _done(behaviour: Behaviour) -> bool:
    return all(a.done for a in actions(behaviour))


def _task_of(behaviour: Behaviour) -> S.TaskAtom:
    node = task_of(behaviour)
    if node is not None:
        return task_atom(node)
    ctx = action_of(behaviour)
    assert ctx is not None, behaviour.name  # a task's sequence, or an action subtree
    step = ctx.step
    return S.TaskAtom(step.name, tuple(step.args))


def candidates(
    shot: Behaviour, root: Behaviour, tree_known: bool, problem_tasks: S.TaskList
) -> Iterator[tuple[Behaviour, list[Behaviour], S.TaskList]]:
    """(sequence, behaviours it replaces, task list to plan), nearest first:
    each enclosing task alone, then together with the tasks after it in its
    parent (so that what those were planned for need not hold any more),
    then the parent."""
    for seq in enclosing_tasks(shot):
        if seq is not root:
            yield seq, [seq], S.TaskList([_task_of(seq)])
            assert seq.parent is not None  # below the root
            siblings = seq.parent.children
            later = siblings[siblings.index(seq) :]
            if len(later) > 1:
                yield seq, later, S.TaskList([_task_of(b) for b in later])
            continue
        pending = [c for c in root.children if not _done(c)]
        yield seq, pending, pending_tasks(root, tree_known, problem_tasks)


def pending_tasks(root: Behaviour, tree_known: bool, problem_tasks: S.TaskList) -> S.TaskList:
    """The top-level tasks of the behaviour tree ``root`` not yet done (one
    partially executed is not done), as a task list to plan again; without
    the plan's task tree, the problem's tasks."""
    if not tree_known:
        return problem_tasks
    return S.TaskList([_task_of(c) for c in root.children if not _done(c)])


def find_repair(
    shot: Behaviour,
    root: Behaviour,
    tree_known: bool,
    domain: S.Domain,
    observed: S.ProblemInstance,
    problem_tasks: S.TaskList,
    functions: FunctionTable | None = None,
) -> tuple[Repair | None, list[str]]:
    """The repair for the failed action subtree ``shot``, and the node paths tried."""
    tried: list[str] = []
    for seq, replaced, tasks in candidates(shot, root, tree_known, problem_tasks):
        path = seq.name if seq is not root else ROOT_NAME
        tried.append(
            path
            if seq is root or len(replaced) == 1
            else f"{path} and the {len(replaced) - 1} task(s) after it"
        )
        if not tasks.items:
            continue
        inst = S.ProblemInstance(observed.state, tasks, observed.pos)
        plan = next(
            Planner(domain, inst, functions, record_trees=True).plans(timeout=PLAN_TIMEOUT), None
        )
        if plan is None:
            continue
        gone = {id(a) for b in replaced for a in actions(b)}
        rest = [a.step for a in actions(root) if not a.done and id(a) not in gone]
        if _applies(domain, observed, functions, [*plan.steps, *rest]):
            return Repair(path, [str(t) for t in _atoms(tasks)], plan, seq, replaced), tried
    return None, tried


def retry_applies(
    ctx: ActionContext,
    root: Behaviour,
    domain: S.Domain,
    observed: S.ProblemInstance,
    functions: FunctionTable | None = None,
) -> bool:
    """Does the failed step ``ctx`` apply again in the observed state, and the
    steps still to come after it? Then trying it again is the smallest repair:
    nothing is re-planned."""
    rest = [a.step for a in actions(root) if not a.done and a is not ctx]
    return _applies(domain, observed, functions, [ctx.step, *rest])


def _atoms(tasks: S.TaskList) -> list[str]:
    from htn.jshop.language.terms import atom_str

    return [atom_str(t.name, t.args) for t in S.task_atoms(tasks)]


def _applies(
    domain: S.Domain,
    observed: S.ProblemInstance,
    functions: FunctionTable | None,
    steps: Iterable[Step],
) -> bool:
    """Do ``steps`` apply in sequence from the observed state?"""
    checker = Planner.for_state(domain, observed.state, functions)
    return all(checker.apply_step(s.name, tuple(s.args)) for s in steps)


def graft(repair: Repair, root: Behaviour, make_action: MakeAction) -> list[Behaviour]:
    """Put the repair's new subtrees into the behaviour tree; returns them."""
    plan, seq = repair.plan, repair.target
    tree = plan.tree
    assert tree is not None  # planned with record_trees
    if seq is not root:
        parent = seq.parent
        assert isinstance(parent, Composite)  # a task's sequence
        at = parent.children.index(repair.replaced[0])
        added = []
        for old, node in zip(repair.replaced, tree.children):
            rebase(node, task_node(old).path)
            parent.remove_child(old)
            added.append(build(node, plan.steps, make_action))
        for k, new in enumerate(added):
            parent.insert_child(new, at + k)
        return added
    assert isinstance(root, Composite)  # the plan's sequence
    for b in repair.replaced:
        root.remove_child(b)
    taken = {c.name for c in root.children}
    names = [n.name for n in tree.children]
    added = []
    for node in tree.children:
        label = label_among(node.name, taken, names.count(node.name))
        taken.add(label)
        rebase(node, label)
        new = build(node, plan.steps, make_action)
        root.add_child(new)
        added.append(new)
    return added
