"""The task tree as log events, so that a log alone shows what ran where.

The task dispatcher gives every task-tree node of a run a number (``node``,
0 for the root) and logs the tree in ``tree`` events:

* one when the dispatcher is built, right after the ``header``: every node
  of the plan's task tree (or, when its decomposition is unknown, the root
  and one node per step), ``replaces`` empty;
* one after each ``replanned`` event: the nodes of the grafted subtrees, new
  numbers, their top nodes under ``parent``, and ``replaces``: the numbers of
  the top nodes whose subtrees they replace (which stay in the log: a
  viewer shows them as replaced).

Every event about an action (``start``, ``verified``, ``fault``,
``replanned``, ...) carries the number of its node as ``node``. A node is
``{"id", "parent", "task", "label"}`` (``label``: the last segment of its
node path, e.g. ``transporting :call 2``), with ``method`` and ``branch`` for
a decomposed task, ``step`` for an operator (1-based: its place in the plan
as executed, as the events' ``step``; for a grafted one, its place in the
repaired plan) and ``holds`` for an action with hold-monitors. Nodes come
depth first in order, so a node's children are the later nodes naming it as
``parent``, in list order. Paths are not logged whole: a path spells all its
ancestors, which would make a deep tree's event quadratic in its depth.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from htn.jshop.plans.tree import TaskTree

    from .behaviours import ActionContext


class NodeNumbers:
    """Numbers for the task-tree nodes of one run, in the order they are logged."""

    def __init__(self) -> None:
        self._ids: dict[int, tuple[int, object]] = {}  # id(node) -> (number, node: kept alive)

    def __len__(self) -> int:
        return len(self._ids)

    def of(self, node: object) -> int | None:
        got = self._ids.get(id(node))
        return None if got is None else got[0]

    def add(self, node: object) -> int:
        number = len(self._ids)
        self._ids[id(node)] = (number, node)
        return number


def tree_nodes(
    top: TaskTree,
    numbers: NodeNumbers,
    parent: int | None,
    step_of: Callable[[TaskTree], int | None],
    action_of: Callable[[TaskTree], ActionContext | None],
) -> list[dict[str, Any]]:
    """The nodes of the task tree ``top`` (depth first), numbered from
    ``len(numbers)`` on; ``top``'s parent is the node numbered ``parent``.
    ``step_of(node)`` is an operator node's 1-based step (or None),
    ``action_of(node)`` its action context (or None): an operator node's
    task is the step as the plan runs it (a task-tree node keeps the
    arguments as they were when its task was decomposed, where a variable may
    have been bound only later), with the action's hold-monitors."""
    out: list[dict[str, Any]] = []
    stack: list[tuple[TaskTree, int | None]] = [(top, parent)]
    while stack:
        node, up = stack.pop()
        number = numbers.add(node)
        d: dict[str, Any] = {
            "id": number,
            "parent": up,
            "task": node.task,
            "label": node.path.rsplit("/", 1)[-1],
        }
        if node.method is not None:
            d["method"] = node.method
            d["branch"] = node.branch
        if node.step is not None:
            d["step"] = step_of(node)
            ctx = action_of(node)
            if ctx is not None:
                d["task"] = ctx.text
                if ctx.holds:
                    d["holds"] = list(ctx.holds)
        out.append(d)
        stack.extend((c, number) for c in reversed(node.children))
    return out


def tree_detail(nodes: list[dict[str, Any]], replaced: int = 0) -> str:
    actions = sum(1 for n in nodes if "step" in n)
    what = f"{len(nodes)} nodes, {actions} actions"
    return (
        f"grafted {what} in place of {replaced} subtree(s)"
        if replaced
        else f"the task tree: {what}"
    )
