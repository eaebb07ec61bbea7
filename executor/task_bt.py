"""The behaviour tree of a plan's task tree: the same shape, node for node.

A compound task becomes a py_trees ``Sequence`` (with memory) named by its
node path (the plan-transformations paper's path, e.g.
``transporting :call 2/fetching``); an operator becomes its action state
machine's subtree (:func:`htn.executor.behaviours.action_subtree`). Every
sequence carries its task-tree node (``htn_task``) and every action subtree
its context (``htn_action``), so the task dispatcher can find the task that
encloses a failed action and graft a repaired subtree in its place.

Without a task tree (a plan read from a file whose decomposition is unknown)
the plan is one sequence of actions. Task trees deeper than ``MAX_DEPTH``
(JSHOP2's recursive domains nest one level per step) are cut there: the
leaves below become children of the sequence at that depth, so ticking
stays shallow.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import py_trees
from py_trees.behaviour import Behaviour

from htn.jshop.language import syntax as S
from htn.jshop.plans.tree import TaskTree

if TYPE_CHECKING:
    from htn.jshop.plans.plan import Step

    from .behaviours import ActionContext

MakeAction = Callable[["Step", TaskTree], Behaviour]  # a step and its node -> its subtree

MAX_DEPTH = 48
ROOT_NAME = "plan"


def flat_tree(steps: Sequence[Step]) -> TaskTree:
    """A task tree that knows only the plan's steps."""
    root = TaskTree(name="", path="")
    root.children = [
        TaskTree(name=s.name, args=tuple(s.args), path=f"step {i + 1}", step=i)
        for i, s in enumerate(steps)
    ]
    return root


def task_atom(node: TaskTree) -> S.TaskAtom:
    return S.TaskAtom(node.name, tuple(node.args))


def build(
    node: TaskTree, steps: Sequence[Step], make_action: MakeAction, depth: int = 0
) -> Behaviour:
    """The behaviour tree of ``node`` (a task-tree node; leaves index ``steps``)."""
    if node.step is not None:
        return make_action(steps[node.step], node)
    top = _sequence(node)
    work: list[tuple[TaskTree, py_trees.composites.Sequence, int]] = [(node, top, depth)]
    while work:  # iterative: task trees can be deep
        task, seq, d = work.pop()
        children = task.children if d < MAX_DEPTH else task.leaves()
        for child in children:
            if child.step is not None:
                seq.add_child(make_action(steps[child.step], child))
            else:
                sub = _sequence(child)
                seq.add_child(sub)
                work.append((child, sub, d + 1))
    return top


def _sequence(node: TaskTree) -> py_trees.composites.Sequence:
    seq = py_trees.composites.Sequence(node.path or ROOT_NAME, memory=True)
    # an attribute of our own on py_trees' behaviour, which does not declare it
    setattr(seq, "htn_task", node)  # noqa: B010
    return seq


def task_of(behaviour: Behaviour) -> TaskTree | None:
    """The task-tree node a task's sequence carries (``htn_task``), else None."""
    node: TaskTree | None = getattr(behaviour, "htn_task", None)
    return node


def action_of(behaviour: Behaviour) -> ActionContext | None:
    """The context the top of an action subtree carries (``htn_action``), else None."""
    ctx: ActionContext | None = getattr(behaviour, "htn_action", None)
    return ctx


def task_node(behaviour: Behaviour) -> TaskTree:
    """The task-tree node of a task's sequence or of an action subtree."""
    node = task_of(behaviour)
    if node is not None:
        return node
    ctx = action_of(behaviour)
    assert ctx is not None and ctx.node is not None, behaviour.name
    return ctx.node


def actions(root: Behaviour) -> list[ActionContext]:
    """The action contexts of a behaviour tree, in plan order."""
    return [ctx for b in root.iterate() if (ctx := action_of(b)) is not None]


def enclosing_tasks(behaviour: Behaviour) -> list[Behaviour]:
    """The sequences above an action subtree, nearest first, the root last."""
    out: list[Behaviour] = []
    node = behaviour.parent
    while node is not None:
        if hasattr(node, "htn_task"):
            out.append(node)
        node = node.parent
    return out


def rebase(tree: TaskTree, new_root_path: str) -> None:
    """Give the nodes of a freshly planned one-task tree the path of the task
    they replace: its top node gets ``new_root_path``, the rest follow."""
    old = tree.path
    for n in tree.walk():
        n.path = new_root_path + n.path[len(old) :]


def label_among(name: str, taken: set[str], count: int) -> str:
    """A node-path label for a new sibling named ``name``, unique among ``taken``."""
    if count == 1 and name not in taken:
        return name
    k = 1
    while f"{name} :call {k}" in taken:
        k += 1
    return f"{name} :call {k}"
