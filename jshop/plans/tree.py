"""Task trees: the decomposition behind one plan (the paper's task network).

A :class:`TaskTree` node is a task with its bound arguments, what decomposed it
(the method and branch label) or achieved it (the operator, with its plan step
index), its children in order, and a stable path such as
``bring_object/fetch_object/grasp_object``; when siblings share a name, each
gets ``:call N`` (1-based) appended, as in the plan-transformations paper:
``transport/transporting :call 2/delivering``.

The planner takes a snapshot of the task network when it finds a plan, so each
plan's tree holds only the decompositions of that plan, never those of a branch
the search backtracked over.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from htn.jshop.language.record import Record
from htn.jshop.language.terms import atom_str, term_str

# A node deeper than this has no path (""): a path spells all its ancestors,
# so a recursion thousands deep (IPC 2020 Towers: pfile_10's 1,023 moves sit
# hundreds of levels down) made the paths quadratic in the plan's length
# (pfile_15 written as JSON: 24 GB); its parent's chain still places it.
PATH_DEPTH = 64


class TaskTree(Record):
    """One node of a task tree; the root is the problem's task list."""

    __slots__ = (
        "name",
        "args",
        "path",
        "method",
        "method_index",
        "branch",
        "step",
        "children",
        "outcome",
        "code_replacement",
    )

    def __init__(
        self,
        name: str,
        args: tuple[Any, ...] = (),
        path: str = "",
        method: str | None = None,
        method_index: int | None = None,
        branch: str | None = None,
        step: int | None = None,
        children: list[TaskTree] | None = None,
        outcome: str | None = None,
        code_replacement: list[str] | None = None,
    ) -> None:
        self.name, self.args, self.path = name, args, path
        self.method = method  # method head name that decomposed it
        self.method_index = method_index  # which of the methods for that task (0-based)
        self.branch = branch  # that method's branch label
        self.step = step  # index in the plan, for primitive tasks
        self.children: list[TaskTree] = [] if children is None else children
        self.outcome = outcome  # after an execution or projection (annotate())
        self.code_replacement = code_replacement  # what a transformation put in its place

    @property
    def primitive(self) -> bool:
        return self.name.startswith("!")

    @property
    def task(self) -> str:
        return atom_str(self.name, self.args) if self.name else "(root)"

    def walk(self) -> Iterator[TaskTree]:
        """Every node, depth first in order (iterative: trees can be thousands deep)."""
        stack = [self]
        while stack:
            node = stack.pop()
            yield node
            stack.extend(reversed(node.children))

    def leaves(self) -> list[TaskTree]:
        return [n for n in self.walk() if n.step is not None]

    def find(self, path: str) -> TaskTree | None:
        for n in self.walk():
            if n.path == path:
                return n
        return None

    def to_dict(self) -> dict[str, Any]:
        """The tree as JSON-ready data, flat so that its depth does not matter
        to JSON readers: ``{"nodes": [...]}``, depth first in order. Each node
        has ``id`` (its index in the list) and ``parent`` (the parent's id;
        None for the root, whose task is ``(root)``), so a node's children are
        the nodes naming it as parent, in list order."""
        nodes: list[dict[str, Any]] = []
        stack: list[tuple[TaskTree, int | None]] = [(self, None)]
        while stack:
            node, parent = stack.pop()
            args = [term_str(a) for a in node.args]
            task = ("(" + " ".join([node.name, *args]) + ")") if node.name else "(root)"
            d: dict[str, Any] = {
                "id": len(nodes),
                "parent": parent,
                "task": task,
                "name": node.name,
                "args": args,
                "path": node.path,
            }
            if node.method is not None:
                d["method"] = node.method
                d["method_index"] = node.method_index
                d["branch"] = node.branch
            if node.step is not None:
                d["step"] = node.step
            if node.outcome is not None:
                d["outcome"] = node.outcome
            if node.code_replacement is not None:
                d["code_replacement"] = node.code_replacement
            nodes.append(d)
            stack.extend((c, d["id"]) for c in reversed(node.children))
        return {"nodes": nodes}

    def to_text(self) -> str:
        """A plain, stable text rendering (used for golden files)."""
        lines = []
        stack = [(c, 0) for c in reversed(self.children)]
        while stack:
            n, depth = stack.pop()
            pad = "  " * depth
            if n.step is not None:
                how = f"step {n.step + 1}"
            elif n.method is not None:
                assert n.method_index is not None  # set with the method
                how = f"method {n.method}#{n.method_index + 1} branch {n.branch}"
            else:
                how = "not decomposed"
            lines.append(f"{pad}{n.task}  [{how}]  @{n.path}")
            stack.extend((c, depth + 1) for c in reversed(n.children))
        return "\n".join(lines) + "\n"

    def to_dot(self) -> str:
        """Graphviz DOT of the tree."""
        out = ["digraph task_tree {", '  node [shape=box, fontname="monospace"];']
        ids: dict[int, str] = {}
        for i, n in enumerate(self.walk()):
            ids[id(n)] = f"n{i}"
            label = n.task if n.name else "root"
            if n.method:
                label += f"\\n[{n.branch}]"
            shape = ", style=rounded" if n.step is not None else ""
            out.append(f'  n{i} [label="{_dot_escape(label)}"{shape}];')
        for n in self.walk():
            for c in n.children:
                out.append(f"  {ids[id(n)]} -> {ids[id(c)]};")
        out.append("}")
        return "\n".join(out) + "\n"


def annotate(tree: TaskTree, step_outcomes: Mapping[int, str]) -> TaskTree:
    """Set each node's outcome from an execution: a leaf gets its step's final
    outcome (``verified``, ``aborted``, ``failed``, or ``not run``); a task is
    ``verified`` when all its children are, else the first other outcome."""
    order = list(tree.walk())
    for node in reversed(order):  # children before parents
        if node.step is not None:
            node.outcome = step_outcomes.get(node.step, "not run")
        elif node.children:
            outs = [c.outcome for c in node.children]
            node.outcome = next((o for o in outs if o != "verified"), "verified")
        elif node.method is not None:  # decomposed into nothing: nothing to do
            node.outcome = "verified"
    return tree


def _dot_escape(s: str) -> str:
    return s.replace("\\", "\\\\").replace('"', '\\"').replace("\\\\n", "\\n")


def snapshot(root: Any, steps: Sequence[Any], paths: bool = True) -> TaskTree:
    """Build the tree of the current task network (a planner ``Node``).

    Without ``paths`` every node's path is left empty (the IPC output does
    not need them), and with them every node deeper than :data:`PATH_DEPTH`."""
    # root is Any: a Node of htn.jshop.search.network, a room above this one
    tree = TaskTree(name="", path="")
    tree.children = _children(root, "", paths)
    return tree


def _flatten(node: Any) -> list[Any]:
    """The task nodes of a task list, nested lists flattened in order."""
    out = []
    stack: list[Iterator[Any]] = [iter(node.subtasks or ())]
    while stack:
        for child in stack[-1]:
            if child.task is not None:
                out.append(child)
            else:
                stack.append(iter(child.subtasks))
            break
        else:
            stack.pop()
    return out


def sibling_paths(parent_path: str, names: Sequence[str], depth: int) -> list[str]:
    """The paths of the children named ``names`` (in order) of a node whose
    path is ``parent_path``, the children at ``depth`` (1: the problem's
    top-level tasks): the parent's path and the child's name, ``:call N``
    among siblings of one name; "" deeper than :data:`PATH_DEPTH`."""
    if depth > PATH_DEPTH:
        return [""] * len(names)
    counts = Counter(names)
    seen: Counter[str] = Counter()
    out = []
    for name in names:
        seen[name] += 1
        label = name if counts[name] == 1 else f"{name} :call {seen[name]}"
        out.append(f"{parent_path}/{label}" if parent_path else label)
    return out


def _children(node: Any, prefix: str, paths: bool = True) -> list[TaskTree]:
    """The subtrees below a network node, built without recursion."""
    out: list[TaskTree] = []
    work: list[tuple[Any, str, list[TaskTree], int]] = [(node, prefix, out, 1)]
    while work:
        parent, path, sink, depth = work.pop()
        kids = _flatten(parent)
        names = [k.task.name for k in kids]
        kpaths = sibling_paths(path, names, depth) if paths else [""] * len(kids)
        for k, name, kpath in zip(kids, names, kpaths):
            t = TaskTree(name=name, args=k.task.args, path=kpath)
            how = k.how
            if isinstance(how, int):
                t.step = how
            elif how is not None:
                method, branch, index = how
                t.method = method.name
                t.method_index = index
                t.branch = method.branches[branch].label
                work.append((k, kpath, t.children, depth + 1))
            sink.append(t)
    return out
