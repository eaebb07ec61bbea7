"""Plan files: what ``htn plan -o`` writes and ``htn run`` reads.

A plan file is JSHOP2's plan output preceded by comment lines naming the
domain and problem files (relative to the plan file)::

    ; htn plan file: JSHOP2 plan format
    ; domain: ../domains/domestic.jshop
    ; problem: ../problems/bring_object.jshop
    Plan cost: 8.0

    (!say jenny task_accepted)
    ...
    --------------------
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field

from .errors import HtnError
from .parser import parse_step
from .plan import Plan, Step


@dataclass
class PlanFile:
    path: str
    domain: str | None = None
    problem: str | None = None
    plans: list = field(default_factory=list)


def read_plan_file(path: str) -> PlanFile:
    if not os.path.isfile(path):
        raise HtnError("no such plan file", path)
    try:
        with open(path, encoding="utf-8") as fh:
            lines = fh.read().splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise HtnError(f"cannot read: {exc}", path)
    base = os.path.dirname(os.path.abspath(path))
    pf = PlanFile(path)
    steps: list = []
    cost = None
    for n, line in enumerate(lines, 1):
        text = line.strip()
        if not text:
            continue
        if text.startswith(";"):
            key, _, value = text.lstrip("; ").partition(":")
            if key.strip() in ("domain", "problem") and value.strip():
                setattr(pf, key.strip(), os.path.normpath(os.path.join(base, value.strip())))
            continue
        if text.startswith("Plan cost:"):
            try:
                cost = float(text.split(":", 1)[1])
            except ValueError:
                raise HtnError("bad plan cost", path, n, 1)
            steps = []
            continue
        if text.startswith("---"):
            if cost is None:
                raise HtnError("plan separator without a 'Plan cost:' line", path, n, 1)
            pf.plans.append(Plan(steps, cost, index=len(pf.plans)))
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
