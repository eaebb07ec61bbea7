"""Plan files: what ``htn plan -o`` writes and ``htn run`` reads.

A plan file is JSHOP2's plan output preceded by comment lines naming the
domain and problem files, relative to the plan file and, as a fallback when
the plan file is moved, absolute (and the ``--functions`` file, if any)::

    ; htn plan file: JSHOP2 plan format
    ; domain: ../domains/domestic.jshop
    ; problem: ../problems/bring_object.jshop
    ; domain (absolute): /home/me/htn/domains/domestic.jshop
    ; problem (absolute): /home/me/htn/problems/bring_object.jshop
    Plan cost: 8.0

    (!say jenny task_accepted)
    ...
    --------------------

Plain JSHOP2 output (no header) is a plan file too; its domain and problem
are then given on the command line. Other ``; key: value`` lines are kept as
notes: ``htn transform -o`` writes the transformed task list as ``; tasks:``.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Optional

from htn.jshop.language.errors import HtnError
from htn.jshop.readers.jshop2 import parse_step
from htn.jshop.readers.source import read_source

from .plan import Plan, Step

NAMED = ("domain", "problem", "functions")


def header(out_path: str, domain: str, problem: str, functions: Optional[str] = None) -> str:
    """The comment lines that name the files a plan was made from."""
    base = os.path.dirname(os.path.abspath(out_path))
    lines = ["; htn plan file: JSHOP2 plan format\n"]
    files = {"domain": domain, "problem": problem, "functions": functions}
    for kind, path in files.items():
        if path:
            lines.append(f"; {kind}: {os.path.relpath(os.path.abspath(path), base)}\n")
    for kind, path in files.items():
        if path:
            lines.append(f"; {kind} (absolute): {os.path.abspath(path)}\n")
    return "".join(lines)


@dataclass
class PlanFile:
    path: str
    plans: list = field(default_factory=list)
    named: dict = field(default_factory=dict)    # "domain" -> [(candidate path, line)]
    notes: dict = field(default_factory=dict)    # other "; key: value" lines -> (value, line)

    def file(self, kind: str) -> Optional[str]:
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
        raise HtnError(f"the {kind} file named here is missing: {shown} (give it with "
                       f"htn run --{kind} FILE)", self.path, candidates[0][1], 1)

    @property
    def domain(self) -> Optional[str]:
        return self.file("domain")

    @property
    def problem(self) -> Optional[str]:
        return self.file("problem")


def read_plan_file(path: str) -> PlanFile:
    if not os.path.isfile(path):
        raise HtnError("no such plan file", path)
    lines = read_source(path).splitlines()     # UTF-8, BOM or not; bad bytes at line:col
    base = os.path.dirname(os.path.abspath(path))
    pf = PlanFile(path)
    steps: list = []
    cost = None
    cost_line = 0
    for n, line in enumerate(lines, 1):
        text = line.strip()
        if not text:
            continue
        if text.startswith(";"):
            key, _, value = text.lstrip("; ").partition(":")
            key, value = key.strip(), value.strip()
            kind = key.removesuffix(" (absolute)")
            if kind in NAMED and value:
                where = os.path.normpath(os.path.join(base, value))
                pf.named.setdefault(kind, []).append((where, n))
            elif key and value:
                pf.notes.setdefault(key, (value, n))
            continue
        if text.startswith("Plan cost:"):
            try:
                cost = float(text.split(":", 1)[1])
            except ValueError:
                raise HtnError("bad plan cost", path, n, 1)
            steps = []
            cost_line = n
            continue
        if text.startswith("---"):
            if cost is None:
                raise HtnError("plan separator without a 'Plan cost:' line", path, n, 1)
            pf.plans.append(Plan(steps, cost, index=len(pf.plans), line=cost_line))
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
        raise HtnError("the last plan is not terminated by '--------------------'", path,
                       len(lines), 1)
    if not pf.plans:
        raise HtnError("the plan file holds no plan", path)
    return pf
