"""Plan files: what ``htn plan -o`` (and ``htn transform -o``) writes and
``htn run`` and ``htn validate`` read.

A plan file is JSHOP2's plan output (manual 3.13: ``Plan cost:``, the steps,
a line of dashes), preceded by comment lines naming the domain and problem
files, relative to the plan file and, as a fallback when the plan file is
moved, absolute (and the ``--functions`` file, if any). Before each plan come
comment lines with its **task tree** (the decomposition the planner found)::

    ; htn plan file: JSHOP2 plan format
    ; domain: ../domains/domestic.jshop
    ; problem: ../problems/bring_object.jshop
    ; domain (absolute): /home/me/htn/domains/domestic.jshop
    ; problem (absolute): /home/me/htn/problems/bring_object.jshop
    ; task tree: 17 nodes
    ; 1 (bring_object jenny pringles guest) method 1 Method0Branch0
    ; 2 (inform jenny task_accepted) method 1 Method12Branch0
    ; 3 step 1
    ; 2 (fetch_object jenny pringles) method 1 Method1Branch0
    ...
    Plan cost: 8.0

    (!say jenny task_accepted)
    ...
    --------------------

Every line htn adds starts with ``;``, a comment to any reader of JSHOP2's
format, and the plan text itself is byte for byte what JSHOP2 prints.

**Task trees.** ``; task tree: N nodes`` is followed by exactly N node lines,
the nodes in depth-first order, each ``; DEPTH WHAT``: DEPTH is 1 for the
problem's top-level tasks and one more for each level below (a node's
children are the lines after it one level deeper, in order); WHAT is

* ``step S``: the primitive task done by step S (1-based) of the plan below;
  the steps appear in plan order, each once, so the leaves are the plan;
* ``(TASK ARGS) method K LABEL``: a compound task reduced by the K-th method
  of that task (1-based, in the domain's order) through its branch LABEL;
* ``(TASK ARGS) unreduced``: a compound task left as it is (no children).

A task is written as JSHOP2 prints it, except that a variable a method left
unbound in it is ``?NAME?SLOT`` (its name and its slot in the bindings), so
that it reads back as the same variable: a repair re-plans the task with it.

Depths (rather than indentation) keep a tree thousands of levels deep linear
in size. Node paths (``bring_object/fetch_object``, ``:call N`` among
siblings of one name; :mod:`htn.jshop.plans.tree`) are not written: they
follow from the names. A tree is read only when a plan is run
(:meth:`PlanFile.tree`); a corrupted one (a count, depth, step or method
that does not fit) is an input error at its ``file:line:col``. ``htn
validate`` and the plan steps ignore these lines. A file without them
(hand-written, from JSHOP2, or from an htn before task trees were written)
is a plan file too: ``htn run`` then recovers a tree by planning again.

Other ``; key: value`` lines are kept as notes: ``htn transform -o`` writes
the transformed task list as ``; tasks:``. Plain JSHOP2 output (no header)
is a plan file too; its domain and problem are then given on the command line.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from htn.jshop.language.digest import sha256_hex
from htn.jshop.language.errors import HtnError
from htn.jshop.language.record import Record
from htn.jshop.readers.source import decode_source

from .plan import Plan, Step
from .tree import TaskTree
from .tree_text import TREE_HEAD, TREE_NODE, read_tree, tree_text

if TYPE_CHECKING:
    from htn.jshop.language import syntax as S
    from htn.jshop.language.syntax import Method

NAMED = ("domain", "problem", "functions")


def header(
    out_path: str,
    domain: str | None,
    problem: str | None,
    functions: str | None = None,
    functions_sha256: str | None = None,
) -> str:
    """The comment lines that name the files a plan was made from
    (``functions_sha256``: of the functions file's bytes as they were loaded;
    a file that is None, such as a domain made in memory, is not named)."""
    base = os.path.dirname(os.path.abspath(out_path))
    lines = ["; htn plan file: JSHOP2 plan format\n"]
    files = {"domain": domain, "problem": problem, "functions": functions}
    for kind, path in files.items():
        if path:
            lines.append(f"; {kind}: {os.path.relpath(os.path.abspath(path), base)}\n")
    for kind, path in files.items():
        if path:
            lines.append(f"; {kind} (absolute): {os.path.abspath(path)}\n")
    if functions and functions_sha256:
        # a plan file is data: htn run imports no file it names, it asks for
        # --functions and checks that this is the file the plans were made with
        lines.append(f"; functions sha256: {functions_sha256}\n")
    return "".join(lines)


def plan_text(plan: Plan) -> str:
    """One plan as a plan file holds it: its task tree (if it has one), then
    exactly what JSHOP2 prints for it."""
    return (tree_text(plan.tree) if plan.tree is not None else "") + plan.to_jshop()


class PlanFile(Record):
    __slots__ = ("path", "plans", "named", "notes", "lines", "sha256", "trees")

    def __init__(
        self,
        path: str,
        plans: list[Plan] | None = None,
        named: dict[str, list[tuple[str, int]]] | None = None,
        notes: dict[str, tuple[str, int]] | None = None,
        lines: list[str] | None = None,
        sha256: str = "",
        trees: list[list[tuple[int, str]] | None] | None = None,
    ) -> None:
        self.path = path
        self.plans: list[Plan] = [] if plans is None else plans
        # "domain" -> [(candidate path, line)]
        self.named: dict[str, list[tuple[str, int]]] = {} if named is None else named
        # other "; key: value" lines -> (value, line)
        self.notes: dict[str, tuple[str, int]] = {} if notes is None else notes
        self.lines: list[str] = [] if lines is None else lines  # the file's text, line by line
        self.sha256 = sha256  # of the file's bytes, as read
        # per plan: its tree's [(line, text)] or None
        self.trees: list[list[tuple[int, str]] | None] = [] if trees is None else trees

    def file(self, kind: str) -> str | None:
        """The ``kind`` ("domain", "problem", "functions") file the header
        names: relative to the plan file if it is there, else the absolute
        path; None if the header names none. A named file found nowhere is
        an error that says how to give it instead."""
        candidates = self.named.get(kind)
        if not candidates:
            return None
        for path, _line in candidates:
            if os.path.isfile(path):
                return path
        shown = " nor ".join(p for p, _ in candidates)
        raise HtnError(
            f"the {kind} file named here is missing: {shown} (give it with htn run --{kind} FILE)",
            self.path,
            candidates[0][1],
            1,
        )

    def named_functions(self) -> tuple[str, int, str | None] | None:
        """(path as written, line, SHA-256 or None) of the functions file the
        plans were made with, if the header names one. It is never loaded
        because of that (see :func:`htn.api.run_inputs.checked_functions`)."""
        candidates = self.named.get("functions")
        if not candidates:
            return None
        digest = self.notes.get("functions sha256", (None,))[0]
        path = next((p for p, _ in candidates if os.path.isfile(p)), candidates[-1][0])
        return path, candidates[0][1], digest

    @property
    def domain(self) -> str | None:
        return self.file("domain")

    @property
    def problem(self) -> str | None:
        return self.file("problem")

    def tree(
        self, index: int, methods: Mapping[str, Sequence[Method]] | None = None
    ) -> TaskTree | None:
        """The task tree written before plan ``index`` (0-based), or None if
        the file holds none for it. ``methods`` (task name -> the domain's
        methods for it) also checks that each method and branch exists and
        takes the task's arguments. A tree that does not fit its plan is an
        input error at its line and column."""
        lines = self.trees[index]
        if lines is None:
            return None
        return read_tree(lines, self.path, self.plans[index].steps, methods)


def read_plan_file(path: str) -> PlanFile:
    """Read a plan file (the file is opened once: its text, lines and
    SHA-256 are kept on the :class:`PlanFile`)."""
    # the JSHOP2 reader only where a plan file is read, not by htn plan
    from htn.jshop.readers.jshop2_fast import Fallback
    from htn.jshop.readers.jshop2_fast import parse_step as fast_step

    def parse_step(text: str, path: str, n: int) -> S.TaskAtom:
        try:
            return fast_step(text, path, n)
        except Fallback:  # not plainly one step: lark's reader, which says where
            from htn.jshop.readers.jshop2 import parse_step as step

            atom: S.TaskAtom = step(text, path, n)
            return atom

    if not os.path.isfile(path):
        raise HtnError("no such plan file", path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise HtnError(f"cannot read: {exc.strerror}", path) from exc
    lines = decode_source(data, path).splitlines()  # UTF-8, BOM or not; bad bytes at line:col
    base = os.path.dirname(os.path.abspath(path))
    pf = PlanFile(path, lines=lines, sha256=sha256_hex(data))
    steps: list[Step] = []
    cost: float | None = None
    cost_line = 0
    tree: list[tuple[int, str]] | None = None  # the task tree lines before the next plan
    in_tree = False
    for n, line in enumerate(lines, 1):
        text = line.strip()
        if not text:
            in_tree = False
            continue
        if text.startswith(";"):
            if TREE_HEAD.match(text):
                if tree is not None:
                    raise HtnError("a second task tree before one plan", path, n, 1)
                tree, in_tree = [(n, text)], True
                continue
            if in_tree and TREE_NODE.match(text):
                assert tree is not None  # in_tree: a tree began
                tree.append((n, text))
                continue
            in_tree = False
            key, _, value = text.lstrip("; ").partition(":")
            key, value = key.strip(), value.strip()
            kind = key.removesuffix(" (absolute)")
            if kind in NAMED and value:
                where = os.path.normpath(os.path.join(base, value))
                pf.named.setdefault(kind, []).append((where, n))
            elif key and value:
                pf.notes.setdefault(key, (value, n))
            continue
        in_tree = False
        if text.startswith("Plan cost:"):
            try:
                cost = float(text.split(":", 1)[1])
            except ValueError:
                raise HtnError("bad plan cost", path, n, 1) from None
            steps = []
            cost_line = n
            continue
        if text.startswith("---"):
            if cost is None:
                raise HtnError("plan separator without a 'Plan cost:' line", path, n, 1)
            pf.plans.append(Plan(steps, cost, index=len(pf.plans), line=cost_line))
            pf.trees.append(tree)
            tree = None
            cost = None
            continue
        if text.startswith("("):
            if cost is None:
                raise HtnError("plan step outside a plan (missing 'Plan cost:' line)", path, n, 1)
            atom = parse_step(text, path, n)
            steps.append(Step(atom.name, atom.args, line=n))
            continue
        raise HtnError(f"unexpected line in plan file: {text[:40]!r}", path, n, 1)
    if cost is not None:
        raise HtnError(
            "the last plan is not terminated by '--------------------'", path, len(lines), 1
        )
    if not pf.plans:
        raise HtnError("the plan file holds no plan", path)
    return pf
