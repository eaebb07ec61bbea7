"""Plans in the IPC 2020 HTN format, which the competition's verifier reads.

The format (pandaPIparser's ``-verify``; the IPC 2020 rules)::

    ==>
    0 drive truck_0 city_loc_2 city_loc_1
    1 pick_up truck_0 city_loc_1 package_0 capacity_0 capacity_1
    root 3 5
    3 deliver package_0 city_loc_0 -> m_deliver_ordering_0 4 1 ...
    4 get_to truck_0 city_loc_1 -> m_drive_to_ordering_0 0
    <==

First the primitive plan, one action per line in execution order: an id, the
action's name and its arguments. Then ``root`` with the ids of the initial
task network's tasks, and one line per decomposition: the id of a compound
task, the task with its arguments, ``->``, the method's name and the ids of
the subtasks it produced in the method's order. Ids are unique across actions
and tasks (actions take 0..n-1, compound tasks the ids after). Names are
printed as the HDDL files spell them (the verifier compares names exactly).
Needs the plan's task tree (the planner records it with ``record_trees``).

:func:`read_ipc_plans` reads the format back (``htn validate``); what it
means for such a plan to be valid is :mod:`htn.jshop.checks.ipc_verify`'s.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

from htn.jshop.language.errors import HtnError
from htn.jshop.language.record import Record
from htn.jshop.language.terms import term_str

if TYPE_CHECKING:
    from .plan import Plan


def ipc_text(plan: Plan, spelling: Mapping[str, str]) -> str:
    """The plan (with its ``tree``) as IPC 2020 text, ``==>`` to ``<==``."""

    def spell(name: str) -> str:
        name = name.lstrip("!")
        return spelling.get(name, name)

    def line(name: str, args: Iterable[Any]) -> str:
        return " ".join([spell(name), *(spell(term_str(a)) for a in args)])

    out = ["==>"]
    out += [f"{i} {line(s.name, s.args)}" for i, s in enumerate(plan.steps)]
    tree = plan.tree
    if tree is None:
        raise ValueError("an IPC plan needs the plan's task tree (plan with record_trees)")
    ids: dict[int, int] = {}
    next_id = len(plan.steps)
    nodes = [n for n in tree.walk() if n is not tree]
    for node in nodes:
        if node.step is not None:
            ids[id(node)] = node.step
        else:
            ids[id(node)] = next_id
            next_id += 1
    out.append("root " + " ".join(str(ids[id(c)]) for c in tree.children))
    for node in nodes:
        if node.step is None:
            children = " ".join(str(ids[id(c)]) for c in node.children)
            method = spell(node.branch or node.method or "")
            out.append(
                f"{ids[id(node)]} {line(node.name, node.args)} -> {method} {children}".rstrip()
            )
    out.append("<==")
    return "\n".join(out) + "\n"


# ------------------------------------------------------------------ reading


class IpcLine(Record):
    """One line of an IPC plan: an action (``method`` None) or a
    decomposition. Names are lower-cased (HDDL names are case-insensitive);
    ``cols`` are the 1-based columns of the name and of each argument."""

    __slots__ = (
        "id",
        "name",
        "args",
        "line",
        "col",
        "cols",
        "method",
        "method_col",
        "children",
        "child_cols",
    )

    def __init__(
        self,
        id: int,
        name: str,
        args: tuple[str, ...],
        line: int,
        col: int,
        cols: tuple[int, ...],
        method: str | None = None,
        method_col: int = 0,
        children: tuple[int, ...] = (),
        child_cols: tuple[int, ...] = (),
    ) -> None:
        self.id, self.name, self.args, self.line = id, name, args, line
        self.col = col  # column of the id
        self.cols = cols  # columns of the name and the arguments
        self.method, self.method_col = method, method_col
        self.children, self.child_cols = children, child_cols

    @property
    def text(self) -> str:
        return " ".join((self.name, *self.args))


class IpcPlan(Record):
    """One ``==>`` ... ``<==`` block of a plan file."""

    __slots__ = (
        "actions",
        "root",
        "root_cols",
        "root_line",
        "decompositions",
        "line",
        "end_line",
        "index",
    )

    def __init__(
        self,
        actions: list[IpcLine] | None = None,
        root: tuple[int, ...] = (),
        root_cols: tuple[int, ...] = (),
        root_line: int = 0,
        decompositions: list[IpcLine] | None = None,
        line: int = 0,
        end_line: int = 0,
        index: int = 0,
    ) -> None:
        self.actions: list[IpcLine] = [] if actions is None else actions  # in execution order
        self.root, self.root_cols, self.root_line = root, root_cols, root_line
        self.decompositions: list[IpcLine] = [] if decompositions is None else decompositions
        self.line = line  # the line of its ``==>``
        self.end_line = end_line  # the line of its ``<==``
        self.index = index


_TOKEN = re.compile(r"[^\s()]+")  # parentheses separate, as in the verifier's reader


def is_ipc_text(text: str) -> bool:
    """True if the text holds an IPC plan: a line that is ``==>``."""
    return any(line.strip() == "==>" for line in text.splitlines())


def read_ipc_plans(text: str, file: str) -> list[IpcPlan]:
    """The ``==>`` ... ``<==`` blocks of a plan file (text before, between and
    after them is ignored, as the competition's verifier ignores a planner's
    log). Raises :class:`HtnError` (``file:line:col``) for a block that
    cannot be read."""
    plans: list[IpcPlan] = []
    current: IpcPlan | None = None
    section = ""
    for n, raw in enumerate(text.splitlines(), 1):
        tokens = [(m.group(), m.start() + 1) for m in _TOKEN.finditer(raw)]
        if current is None:
            if raw.strip() == "==>":
                current = IpcPlan(line=n, index=len(plans))
                section = "actions"
            continue
        if not tokens:
            continue
        head, col = tokens[0]
        if head == "<==":
            current.end_line = n
            plans.append(current)
            current = None
            continue
        if head == "==>":
            raise HtnError(
                f"a new plan starts before the plan of line {current.line} ends with '<=='",
                file,
                n,
                col,
            )
        if head == "root":
            if section != "actions":
                raise HtnError(
                    f"a second 'root' line (the first is line {current.root_line})", file, n, col
                )
            current.root = tuple(_ident(t, c, file, n) for t, c in tokens[1:])
            current.root_cols = tuple(c for _, c in tokens[1:])
            current.root_line = n
            section = "methods"
            continue
        ident = _ident(head, col, file, n)
        if len(tokens) < 2 or tokens[1][0] == "->":
            raise HtnError(
                f"line {ident}: an action or task name must follow the id",
                file,
                n,
                tokens[1][1] if len(tokens) > 1 else col,
            )
        arrow = next((i for i, (t, _) in enumerate(tokens) if t == "->"), None)
        if section == "actions":
            if arrow is not None:
                raise HtnError(
                    "a decomposition line ('->') before the 'root' line", file, n, tokens[arrow][1]
                )
            current.actions.append(_line(ident, col, tokens[1:], n))
            continue
        if arrow is None:
            raise HtnError(
                "a decomposition line needs '-> METHOD SUBTASK-IDS' after the task",
                file,
                n,
                tokens[-1][1] + len(tokens[-1][0]),
            )
        if arrow + 1 >= len(tokens):
            raise HtnError("a method name must follow '->'", file, n, tokens[arrow][1])
        entry = _line(ident, col, tokens[1:arrow], n)
        entry.method, entry.method_col = tokens[arrow + 1][0].lower(), tokens[arrow + 1][1]
        rest = tokens[arrow + 2 :]
        entry.children = tuple(_ident(t, c, file, n) for t, c in rest)
        entry.child_cols = tuple(c for _, c in rest)
        current.decompositions.append(entry)
    if current is not None:
        raise HtnError(
            f"the plan of line {current.line} does not end with '<=='", file, current.line, 1
        )
    if not plans:
        raise HtnError("the file holds no IPC plan (a '==>' ... '<==' block)", file)
    return plans


def _ident(token: str, col: int, file: str, line: int) -> int:
    if not token.isdigit():
        raise HtnError(f"expected a task id (a number 0, 1, ...), found {token!r}", file, line, col)
    return int(token)


def _line(ident: int, col: int, tokens: list[tuple[str, int]], line: int) -> IpcLine:
    return IpcLine(
        ident,
        tokens[0][0].lower(),
        tuple(t.lower() for t, _ in tokens[1:]),
        line,
        col,
        tuple(c for _, c in tokens),
    )
