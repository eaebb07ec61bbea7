"""The validate use case: replay plans from a problem's initial state with a
domain's operators (``htn validate``; JSHOP2 manual 5.2.1).

A plan is valid when every step's precondition holds in the state its
predecessors reach, no step deletes a protected atom, the plan's cost is the
sum of its steps' costs and (HDDL) the problem's goal holds at the end
(:mod:`htn.jshop.checks.validate`). A step that names no operator of the
domain, or with the wrong arity, is bad input (an :class:`HtnError`), not an
invalid plan. Task trees in a plan file are not read: a plan file is
validated as the JSHOP2 plan text it holds.

A plan file in the IPC 2020 format (``htn plan -f ipc``) is checked as the
competition's verifier does, decompositions included
(:func:`validate_ipc`, :mod:`htn.jshop.checks.ipc_verify`).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, cast

from htn.jshop.checks.validate import Verdict, check_steps, validate_plan
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import Guard
from htn.jshop.plans.plan import Plan
from htn.jshop.plans.planfile import PlanFile, read_plan_file

from .inputs import domain_and_problem, function_table, is_path

if TYPE_CHECKING:
    from htn.jshop.checks.ipc_verify import IpcVerdict
    from htn.jshop.plans.ipc import IpcPlan

    from .inputs import DomainInput, FunctionsInput, ProblemInput, StrPath


@dataclass
class PlanVerdict:
    """One plan and its verdict; ``file`` is the plan file it was read from."""

    plan: Plan
    verdict: Verdict
    file: str | None = None

    @property
    def valid(self) -> bool:
        return self.verdict.valid

    @property
    def where(self) -> str | None:
        """``FILE:LINE:1`` of the step (or cost) that fails, or the file."""
        if self.verdict.line and self.file:
            return f"{self.file}:{self.verdict.line}:1"
        return self.file

    @property
    def failed_step(self) -> int | None:
        """The 1-based step that fails (None: the plan as a whole, e.g. its cost)."""
        v = self.verdict
        if v.failed_step is not None and v.failed_step < v.steps:
            return v.failed_step + 1
        return None


def validate(
    domain: DomainInput,
    problem: ProblemInput,
    plan: StrPath | PlanFile | Plan | Iterable[Plan],
    *,
    plan_index: int | None = None,
    functions: FunctionsInput = None,
    stops: Guard | None = None,
) -> list[PlanVerdict]:
    """The verdict on each plan of ``plan`` (a plan file's path, a
    :class:`~htn.jshop.plans.planfile.PlanFile`, a
    :class:`~htn.jshop.plans.plan.Plan` or a list of them), in order;
    ``plan_index`` (1-based) picks one plan of a file. ``domain``,
    ``problem``, ``functions``: paths or loaded objects (:mod:`htn.api.inputs`)."""
    table = function_table(functions, stops)
    dom, prob = domain_and_problem(domain, problem, table)
    file: str | None = None
    if is_path(plan):
        plan = read_plan_file(os.fspath(plan))
    if isinstance(plan, PlanFile):
        file, plans = plan.path, plan.plans
    elif isinstance(plan, Plan):
        plans = [plan]
    else:
        plans = list(cast(Iterable[Plan], plan))  # a path was read above
    if plan_index is not None:
        if plan_index > len(plans):
            raise HtnError(f"--plan-index {plan_index}: the file holds {len(plans)} plan(s)", file)
        plans = [plans[plan_index - 1]]
    instance = prob.instances[0]
    for p in plans:
        check_steps(dom, p.steps, file)
    return [PlanVerdict(p, validate_plan(dom, instance, p, table), file) for p in plans]


def ipc_text(path: object) -> str | None:
    """The text of the plan file ``path`` if it holds IPC-format plans
    (``==>`` ... ``<==``), else None."""
    from htn.jshop.plans.ipc import is_ipc_text
    from htn.jshop.readers.source import read_source

    if not is_path(path) or not os.path.isfile(path):
        return None
    text = read_source(os.fspath(path))
    return text if is_ipc_text(text) else None


def validate_ipc(
    domain: DomainInput,
    problem: ProblemInput,
    plan: StrPath,
    *,
    plan_index: int | None = None,
    functions: FunctionsInput = None,
    text: str | None = None,
    stops: Guard | None = None,
) -> list[tuple[IpcPlan, IpcVerdict]]:
    """``[(IpcPlan, IpcVerdict)]`` for each IPC plan of the file ``plan``
    (``text``: its text, if read already): the actions replayed, every
    decomposition line checked against the domain's methods, every action
    reached from the root exactly once, and the goal, as pandaPIparser
    ``--verify`` checks them (:func:`~htn.jshop.checks.ipc_verify.verify_ipc_plan`)."""
    from htn.jshop.checks.ipc_verify import verify_ipc_text
    from htn.jshop.readers.source import read_source

    table = function_table(functions, stops)
    dom, prob = domain_and_problem(domain, problem, table)
    file = os.fspath(plan)
    if text is None:
        text = read_source(file)
    return verify_ipc_text(dom, prob, text, file, plan_index, table)
