"""The task network of the JSHOP2 search (manual 5.2.3): a tree of
:class:`Node` s that the planner rewrites in place and restores on
backtracking, and which of its tasks may be done next.

* a :class:`Task` is a bound task atom; a :class:`Node` is a task list, or an
  atomic node holding one task until a method or operator reduces it;
* :func:`first_tasks` are the tasks with no unfinished predecessor in an
  ordered list (any task of an unordered one, in the manual's ``getFirst``
  order; in a partially ordered one (HDDL, ``Node.ordered`` a
  :class:`~htn.jshop.language.syntax.PartialOrder`), those of every member
  whose predecessors are all finished, in member order); an ``:immediate``
  one among them is the only option. Nodes marked
  done go on a trail, undone on backtracking (:func:`undo_marks`).
"""

from __future__ import annotations

from htn.jshop.language import syntax as S
from htn.jshop.language.syntax import PartialOrder
from htn.jshop.language.terms import atom_str, subst
from htn.jshop.logic.task_lists import task_list_maker, task_list_warming


class Task:
    """A task instance in the network: a bound task atom."""

    __slots__ = ("name", "args", "immediate", "primitive", "src")

    def __init__(self, name, args, immediate, src=None):
        self.name = name
        self.args = args
        self.immediate = immediate
        self.primitive = name[0] == "!"
        self.src = src

    def __str__(self) -> str:
        return atom_str(self.name, self.args)


class Node:
    """A task list in the network; atomic while ``subtasks`` is None.

    ``how`` records what reduced an atomic node (for the task tree): a
    ``(method, branch_index, method_index)`` triple or the plan step's index.
    """

    __slots__ = ("task", "subtasks", "ordered", "how", "done", "start", "loop_key")

    def __init__(self, task=None, subtasks=None, ordered=True):
        self.task = task
        self.subtasks = subtasks
        self.ordered = ordered
        self.how = None
        self.done = False  # cached: every task below is achieved
        self.start = 0  # cached: members before this index are achieved
        self.loop_key = None  # the active task instance it is, see loops.py


def compile_tasks(tl, what: str = "task list", install=None):
    """Compile a task list into ``env -> [Node]`` (its bound subtasks);
    ``what`` names the generated code. With ``install``, the maker is
    warming (:func:`htn.jshop.logic.task_lists.task_list_warming`)."""
    if install is not None:
        return task_list_warming(tl, Node, Task, what, install)
    return task_list_maker(tl, Node, Task, what)


def bind_tasks(tl: S.TaskList, env: list) -> Node:
    """The node of a task list bound by ``env``, built directly: the
    problem's task list is bound once, and may be long (compiling it would
    cost more than it saves)."""
    return Node(
        None,
        [
            bind_tasks(x, env)
            if isinstance(x, S.TaskList)
            else Node(Task(x.name, subst(x.args, env), x.immediate, x))
            for x in tl.items
        ],
        tl.order_flag,
    )


def first_tasks(root: Node, trail: list | None = None, path: list | None = None) -> list:
    """JSHOP2's ``TaskList.getFirst``, without recursion.

    An ordered list contributes the first tasks of its first non-empty member;
    an unordered list those of every member; an immediate task, wherever it is
    met, is then the only option.

    With a ``trail``, what is found achieved is cached for later calls: a
    member with nothing left is marked ``done``, and a list's ``start`` moves
    past its achieved leading members. Each change is pushed on the trail; the
    planner undoes those made below a search frame when it backtracks into it.

    With a ``path`` (an empty list), an ordered network's walk leaves in it
    where the task found is (see :func:`_first_in_order`); it is emptied if
    the general way was taken.
    """
    if trail is not None and root.ordered:
        found = first_in_order(root, trail, path)
        if found is not None:
            return found
    if path:
        path.clear()
    return _first_tasks(root, trail)


def first_in_order(
    root: Node, trail: list, path: list | None = None, at: tuple | None = None
) -> list | None:
    """:func:`first_tasks` while every list met is ordered (the common case,
    and all of HDDL): one walk down to the first task left; None when an
    unordered list is met (the caller then takes the general way).

    ``path`` is left holding the ``(list, index)`` of each ancestor of the
    task found, its own last. A later walk can resume from there (``at``, the
    task's own entry popped off ``path``) instead of walking down from the
    root again: the planner's cursor, which makes a long tail recursion
    linear rather than quadratic (see ``Planner._first``).
    """
    if path is None:
        path = []
    node, i = at if at is not None else (root, root.start)
    while True:
        subs = node.subtasks
        n = len(subs)
        while i < n:
            child = subs[i]
            cs = child.subtasks
            if cs is None:
                path.append((node, i))
                return [child]
            if cs and not child.done:
                if not child.ordered:
                    return None
                path.append((node, i))
                node, i = child, child.start
                break
            if i == node.start:
                trail.append((node, i))
                node.start = i + 1
            i += 1
        else:
            if not path:
                return []
            node.done = True
            trail.append(node)
            node, i = path.pop()
            i += 1


def _first_tasks(root: Node, trail: list | None) -> list:
    res: list = []
    # (list, next member, len(res) on entry, open members) of each ancestor;
    # ``open_`` is the set of unfinished members of a partially ordered list
    # seen so far (None for other lists): a member may start when none of
    # its predecessors is open (members are in a topological order)
    stack: list = []
    node, i, n0 = root, root.start, 0
    order = node.ordered
    open_: set | None = set() if type(order) is PartialOrder else None
    while True:
        subs = node.subtasks
        n = len(subs)
        down = False
        while i < n:
            child = subs[i]
            i += 1
            cs = child.subtasks
            if open_ is not None and not open_.isdisjoint(order[i - 1]):
                if cs is None or (cs and not child.done):
                    open_.add(i - 1)  # waits for a predecessor
                continue
            if cs is None:
                if child.task.immediate:
                    return [child]
                res.append(child)
                if open_ is not None:
                    open_.add(i - 1)
                elif order:
                    break
            elif cs and not child.done:
                stack.append((node, i, n0, open_))
                node, i, n0 = child, child.start, len(res)
                order = child.ordered
                open_ = set() if type(order) is PartialOrder else None
                down = True
                break
            elif trail is not None and i - 1 == node.start:
                trail.append((node, i - 1))
                node.start = i
        if down:
            continue
        # ``node`` is finished: exhausted, or ordered and it gave a task
        while True:
            if trail is not None and len(res) == n0 and stack:
                node.done = True
                trail.append(node)
            if not stack:
                return res
            child_n0 = n0
            node, i, n0, open_ = stack.pop()
            order = node.ordered
            if open_ is not None:
                if len(res) != child_n0:
                    open_.add(i - 1)
                break
            if not (order and len(res) != n0):
                break


def undo_marks(trail: list, mark: int, loops=None) -> None:
    """Forget what :func:`first_tasks` cached since ``mark``."""
    while len(trail) > mark:
        entry = trail.pop()
        if type(entry) is tuple:
            entry[0].start = entry[1]
        else:
            entry.done = False
            if loops is not None:
                loops.reopened(entry)


def deepest_task(root: Node, req: Node) -> Task | None:
    """The task to name when the search is too deep: the one just reduced, or
    else the deepest reduced compound task of the network."""
    if req.task is not None and not req.task.primitive:
        return req.task
    best, best_depth = None, -1
    stack = [(root, 0)]
    while stack:
        node, depth = stack.pop()
        if node.task is not None and node.subtasks is not None and not node.task.primitive:
            depth += 1
            if depth > best_depth:
                best, best_depth = node.task, depth
        for child in node.subtasks or ():
            stack.append((child, depth))
    return best
