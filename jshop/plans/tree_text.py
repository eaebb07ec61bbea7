"""The text form of a task tree in a plan file: comment lines, one per node,
depth first (the format is described in :mod:`htn.jshop.plans.planfile`).

:func:`tree_text` writes a :class:`~htn.jshop.plans.tree.TaskTree`;
:func:`read_tree` reads one back against its plan's steps (and, given the
domain's methods, checks each method and branch), refusing a corrupted
tree with the ``file:line:col`` of the line that does not fit.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from htn.jshop.language.errors import HtnError
from htn.jshop.language.terms import Var, term_str

from .tree import TaskTree, sibling_paths

if TYPE_CHECKING:
    from htn.jshop.language.syntax import Method

    from .plan import Step

    _Methods = Mapping[str, Sequence[Method]]  # task name -> the domain's methods

TREE_HEAD = re.compile(r";\s*task tree:\s*(\S*)\s*nodes?\s*$")
"""The line that begins a tree: ``; task tree: N nodes``."""
TREE_NODE = re.compile(r";\s*\d")
"""A node line: ``; DEPTH ...``."""


def tree_text(tree: TaskTree) -> str:
    """The comment lines of a task tree (see the module docstring)."""
    out: list[str] = []
    stack = [(c, 1) for c in reversed(tree.children)]
    while stack:
        node, depth = stack.pop()
        if node.step is not None:
            out.append(f"; {depth} step {node.step + 1}\n")
            continue
        if node.method is not None:
            assert node.method_index is not None  # set with the method
            how = f"method {node.method_index + 1} {node.branch}"
        else:
            how = "unreduced"
        out.append(f"; {depth} {_atom_text(node.name, node.args)} {how}\n")
        stack.extend((c, depth + 1) for c in reversed(node.children))
    return f"; task tree: {len(out)} nodes\n" + "".join(out)


def read_tree(
    lines: list[tuple[int, str]],
    path: str,
    steps: Sequence[Step],
    methods: _Methods | None = None,
) -> TaskTree:
    """The tree of ``lines`` (``(line number, text)``: the header, then the
    nodes), whose leaves index ``steps``; ``methods`` (task name -> methods)
    also checks the decompositions against the domain."""
    return _TreeReader(path, steps, methods).read(lines)


class _TreeReader:
    """Reads the lines of one task tree (see the module docstring) into a
    :class:`TaskTree` whose leaves index ``steps``."""

    def __init__(self, path: str, steps: Sequence[Step], methods: _Methods | None) -> None:
        self.path, self.steps, self.methods = path, steps, methods

    def error(self, message: str, n: int, text: str = "", token: str = "") -> HtnError:
        col = text.find(token) + 1 if token and token in text else 1
        return HtnError(f"task tree: {message}", self.path, n, col)

    def read(self, lines: list[tuple[int, str]]) -> TaskTree:
        (head_line, head), nodes = lines[0], lines[1:]
        match = TREE_HEAD.match(head)
        assert match is not None  # the lines begin with the header
        count = match.group(1)
        if not count.isdigit():
            raise self.error(f"{count!r} is not a number of nodes", head_line, head, count)
        if int(count) != len(nodes):
            raise self.error(
                f"the header says {count} nodes, {len(nodes)} follow", head_line, head, count
            )
        root = TaskTree(name="", path="")
        stack: list[tuple[int, TaskTree]] = [
            (0, root)
        ]  # (depth, node) from the root down to the last node
        next_step = 0
        for n, text in nodes:
            depth_text, _, rest = text.lstrip("; ").partition(" ")
            depth = int(depth_text) if depth_text.isdigit() else -1
            if depth < 1 or depth > stack[-1][0] + 1:
                raise self.error(
                    f"depth {depth_text} does not follow depth {stack[-1][0]} "
                    f"(a node is at most one level below the one before)",
                    n,
                    text,
                    depth_text,
                )
            del stack[depth:]
            parent = stack[-1][1]
            if parent.step is not None or (parent is not root and parent.method is None):
                raise self.error(
                    f"{parent.task} has no children (it is not reduced by a method)",
                    n,
                    text,
                    depth_text,
                )
            node = (
                self.step_node(n, text, rest, next_step)
                if rest.startswith("step")
                else self.task_node(n, text, rest)
            )
            if node.step is not None:
                next_step += 1
            parent.children.append(node)
            stack.append((depth, node))
        if next_step != len(self.steps):
            raise self.error(
                f"the tree has {next_step} of the plan's {len(self.steps)} steps", head_line
            )
        _set_paths(root)
        return root

    def step_node(self, n: int, text: str, rest: str, expected: int) -> TaskTree:
        number = rest[len("step") :].strip()
        if not number.isdigit():
            raise self.error(f"expected 'step N', found {rest!r}", n, text, rest)
        if int(number) != expected + 1:
            raise self.error(
                f"step {number} out of order: the plan's next step is {expected + 1}"
                if expected < len(self.steps)
                else f"step {number}: the plan has {len(self.steps)} steps",
                n,
                text,
                number,
            )
        step = self.steps[expected]
        return TaskTree(name=step.name, args=tuple(step.args), step=expected)

    def task_node(self, n: int, text: str, rest: str) -> TaskTree:
        from htn.jshop.readers.jshop2 import parse_step  # lark: only to read a tree

        end = _atom_end(rest)
        if end is None:
            raise self.error("expected 'step N' or a task '(name args...)'", n, text, rest)
        offset = text.find(rest)
        try:
            atom = parse_step(rest[:end], self.path, n)
        except HtnError as exc:
            raise HtnError(
                f"task tree: {exc.message}", self.path, n, offset + (exc.col or 1)
            ) from None
        how = rest[end:].split()
        node = TaskTree(name=atom.name, args=_with_indices(tuple(atom.args)))
        if how == ["unreduced"]:
            return node
        if len(how) != 3 or how[0] != "method" or not how[1].isdigit() or int(how[1]) < 1:
            shown = " ".join(how) or "nothing"
            raise self.error(
                f"expected 'method K LABEL' or 'unreduced' after the task, found {shown!r}",
                n,
                text,
                how[0] if how else "",
            )
        node.method, node.method_index, node.branch = atom.name, int(how[1]) - 1, how[2]
        if self.methods is not None:
            self.check_method(node, n, text, how)
        return node

    def check_method(self, node: TaskTree, n: int, text: str, how: list[str]) -> None:
        # set by task_node, which calls this with the domain's methods only
        assert self.methods is not None and node.method_index is not None
        assert node.branch is not None
        methods = self.methods.get(node.name, [])
        if not methods:
            raise self.error(f"the domain has no method for {node.name}", n, text, node.name)
        if node.method_index >= len(methods):
            raise self.error(
                f"the domain has {len(methods)} method(s) for {node.name}, not {how[1]}",
                n,
                text,
                f"method {how[1]}",
            )
        method = methods[node.method_index]
        if len(method.head.args) != len(node.args):
            raise self.error(
                f"method {how[1]} of {node.name} takes "
                f"{len(method.head.args)} argument(s), the task has "
                f"{len(node.args)}",
                n,
                text,
                node.name,
            )
        labels = [b.label for b in method.branches]
        if node.branch not in labels:
            raise self.error(
                f"method {how[1]} of {node.name} has no branch {node.branch} "
                f"(its branches: {', '.join(labels)})",
                n,
                text,
                node.branch,
            )


def _atom_text(name: str, args: Iterable[Any]) -> str:
    """A task as a tree line writes it: as JSHOP2 prints it, but a variable
    as ``?NAME?INDEX``, so that it reads back as the same variable."""
    return "(" + " ".join([name, *map(_term_text, args)]) + ")"


def _term_text(t: Any) -> str:
    if type(t) is Var:
        return f"{t.name}?{t.index}"
    if type(t) is tuple and t:
        return "(" + " ".join(map(_term_text, t)) + ")"
    return term_str(t)


_INDEXED = re.compile(r"(.*)\?(\d+)$")


def _with_indices(t: Any) -> Any:
    """The variables of a term read from a tree line with their slots back."""
    if type(t) is Var:
        m = _INDEXED.match(t.name)
        return Var(m.group(1), int(m.group(2))) if m else t
    if type(t) is tuple:
        return tuple(_with_indices(x) for x in t)
    return t


def _atom_end(text: str) -> int | None:
    """The end of the parenthesised atom ``text`` starts with, or None."""
    if not text.startswith("("):
        return None
    depth = 0
    for i, c in enumerate(text):
        depth += (c == "(") - (c == ")")
        if depth == 0:
            return i + 1
    return None


def _set_paths(root: TaskTree) -> None:
    """Node paths as the planner gives them (:func:`htn.jshop.plans.tree.sibling_paths`)."""
    work = [(root, 1)]
    while work:
        node, depth = work.pop()
        kids = node.children
        for child, path in zip(kids, sibling_paths(node.path, [c.name for c in kids], depth)):
            child.path = path
            work.append((child, depth + 1))
