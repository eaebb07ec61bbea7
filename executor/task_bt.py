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

from typing import Callable, Optional

import py_trees

from htn.jshop.language import syntax as S
from htn.jshop.plans.tree import TaskTree

MAX_DEPTH = 48
ROOT_NAME = "plan"


def flat_tree(steps) -> TaskTree:
    """A task tree that knows only the plan's steps."""
    root = TaskTree(name="", path="")
    root.children = [
        TaskTree(name=s.name, args=tuple(s.args), path=f"step {i + 1}", step=i)
        for i, s in enumerate(steps)
    ]
    return root


def task_atom(node: TaskTree) -> S.TaskAtom:
    return S.TaskAtom(node.name, tuple(node.args))


def build(node: TaskTree, steps, make_action: Callable, depth: int = 0):
    """The behaviour tree of ``node`` (a task-tree node; leaves index ``steps``)."""
    if node.step is not None:
        return make_action(steps[node.step], node)
    top = _sequence(node)
    work = [(node, top, depth)]
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
    seq.htn_task = node
    return seq


def actions(root) -> list:
    """The action contexts of a behaviour tree, in plan order."""
    return [b.htn_action for b in root.iterate() if hasattr(b, "htn_action")]


def enclosing_tasks(behaviour) -> list:
    """The sequences above an action subtree, nearest first, the root last."""
    out = []
    node = behaviour.parent
    while node is not None:
        if hasattr(node, "htn_task"):
            out.append(node)
        node = node.parent
    return out


def rebase(tree: TaskTree, new_root_path: Optional[str]) -> None:
    """Give the nodes of a freshly planned one-task tree the path of the task
    they replace: its top node gets ``new_root_path``, the rest follow."""
    old = tree.path
    for n in tree.walk():
        n.path = new_root_path + n.path[len(old) :]


def label_among(name: str, taken: set, count: int) -> str:
    """A node-path label for a new sibling named ``name``, unique among ``taken``."""
    if count == 1 and name not in taken:
        return name
    k = 1
    while f"{name} :call {k}" in taken:
        k += 1
    return f"{name} :call {k}"
