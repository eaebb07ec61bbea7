"""What a run needs before the robot moves, read once and checked: the plan
(a plan file, one already read, or a plan object), its domain and problem,
the user functions, the retry limits, and the plan's task tree.

The plan file is opened once: its text gives the steps, the task trees
(:mod:`htn.jshop.plans.planfile`), the lines that locate a bad step, and
the SHA-256 the log's header records. ``htn run --from-log`` reads the log's
header and the plan file it names (:func:`read_run_log`), once each.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from htn.executor.config import load_retries, parse_overrides
from htn.executor.log_header import (
    check_plan_digest,
    check_plan_present,
    check_unchanged,
    read_header,
)
from htn.jshop.checks.recover import RECOVER_PLANS, RECOVER_TIMEOUT, check_runnable, recover_tree
from htn.jshop.checks.validate import check_steps
from htn.jshop.language import syntax as S
from htn.jshop.language.errors import HtnError
from htn.jshop.language.functions import FunctionTable, Guard
from htn.jshop.plans.plan import Plan
from htn.jshop.plans.planfile import PlanFile, read_plan_file

from .inputs import (
    DomainInput,
    FunctionsInput,
    ProblemInput,
    StrPath,
    domain_and_problem,
    function_table,
    is_path,
    path_of,
)

if TYPE_CHECKING:
    from htn.jshop.plans.tree import TaskTree

# a plan to run: a plan file's path, a plan file read, or a plan object
PlanInput = StrPath | PlanFile | Plan
# retry limits: {"grasp": 3}, "grasp=3,place=1", or several such texts
RetriesInput = dict[str, int] | str | Iterable[str] | None


@dataclass
class RunInputs:
    """A plan ready to run: everything read and checked."""

    domain: S.Domain
    problem: S.Problem
    instance: S.ProblemInstance  # the instance whose state is the world
    plan: Plan
    functions: FunctionTable
    limits: dict[str, int]  # retry limits by operator ('!grasp': 2)
    tree: TaskTree | None  # the task tree to execute, or None (one sequence)
    plan_file: str | None  # where the plan was read from (None: a plan object)
    plan_sha256: str | None
    plan_index: int
    files: dict[str, str | None]  # "domain", "problem", "functions" -> path or None
    notes: list[str]  # one line each, e.g. how the tree was found


def load_plan(plan: PlanInput) -> tuple[PlanFile | None, Plan | None]:
    """A plan file (read from a path, or as given) or a plan object."""
    if is_path(plan):
        return read_plan_file(os.fspath(plan)), None
    if isinstance(plan, PlanFile):
        return plan, None
    if isinstance(plan, Plan):
        return None, plan
    raise HtnError(
        f"expected a plan (a plan file's path, a PlanFile or a Plan), got {type(plan).__name__}"
    )


def run_inputs(
    plan: PlanInput,
    domain: DomainInput | None = None,
    problem: ProblemInput | None = None,
    functions: FunctionsInput = None,
    plan_index: int = 1,
    retries: RetriesInput = None,
    stops: Guard | None = None,
) -> RunInputs:
    """Read and check everything a run of ``plan`` needs (see :func:`htn.api.run.run`)."""
    pf, given = load_plan(plan)
    where = pf.path if pf else None
    chosen: Plan
    if pf is not None:
        domain = domain or pf.domain
        problem = problem or pf.problem
        functions = checked_functions(pf.named_functions(), functions, where, stops=stops)
        if not domain or not problem:
            raise HtnError(
                "the plan file names no domain or problem (write it with 'htn plan "
                "-o', or give --domain and --problem)",
                where,
            )
        if plan_index > len(pf.plans):
            raise HtnError(
                f"--plan-index {plan_index}: the file holds {len(pf.plans)} plan(s)", where
            )
        chosen = pf.plans[plan_index - 1]
    else:
        if domain is None or problem is None:
            raise HtnError("a plan object runs with a domain and a problem: give both")
        assert given is not None  # load_plan gives a plan file or a plan
        chosen = given
    table = function_table(functions, stops)
    dom, prob = domain_and_problem(domain, problem, table)
    number = getattr(chosen, "instance", 0) if pf is None else 0
    instance = prob.instances[number if number < len(prob.instances) else 0]
    check_steps(dom, chosen.steps, where)
    domain_file = path_of(dom) or path_of(domain)
    limits = load_retries(domain_file, dom.operators)
    overrides = _overrides(retries)
    unknown = sorted(op for op in overrides if op not in dom.operators)
    if unknown:
        raise HtnError(f"--retries: the domain {dom.name} has no operator {', '.join(unknown)}")
    limits.update(overrides)
    check_runnable(dom, instance, chosen, where, table, pf.lines if pf else ())
    notes: list[str] = []
    tree: TaskTree | None
    if pf is not None:
        tree = pf.tree(plan_index - 1, methods_of(dom, instance))
        source = f"{where}: plan {plan_index}"
    else:
        tree = chosen.tree
        source = "the plan"
    if tree is None:
        tasks = pf.notes.get("tasks", (None,))[0] if pf else None
        tree = recover_tree(dom, instance, chosen.steps, table, tasks=tasks)
        notes.append(
            f"{source} has no task tree: "
            + (
                "recovered one by planning again"
                if tree is not None
                else f"planning again found none ({RECOVER_PLANS} plans, "
                f"{RECOVER_TIMEOUT:g} s), so it runs as one sequence of actions"
            )
        )
    files = {
        "domain": path_of(domain) or path_of(dom),
        "problem": path_of(problem) or path_of(prob),
        "functions": table.source,
    }
    return RunInputs(
        dom,
        prob,
        instance,
        chosen,
        table,
        limits,
        tree,
        where,
        pf.sha256 if pf else None,
        plan_index,
        files,
        notes,
    )


def _overrides(retries: RetriesInput) -> dict[str, int]:
    """Retry limits given as a mapping (``{"grasp": 3}``) or as ``--retries``
    texts (``["grasp=3,place=1"]``), by operator name (``!grasp``)."""
    if retries is None:
        return {}
    if isinstance(retries, dict):
        return parse_overrides([f"{k}={v}" for k, v in retries.items()])
    if isinstance(retries, str):
        return parse_overrides([retries])
    return parse_overrides(list(retries))


def methods_of(domain: S.Domain, instance: S.ProblemInstance) -> dict[str, list[S.Method]]:
    """The methods a task tree of ``instance`` may use: the domain's, and for
    an HDDL problem with parameters the artificial root task's."""
    if getattr(instance, "top", None) is None:
        return domain.methods
    top = S.root_method(instance)
    return {**domain.methods, top.name: [top]}


def checked_functions(
    named: tuple[str, int, str | None] | None,
    given: FunctionsInput,
    where: str | None,
    line: int | None = None,
    option: str = "--functions",
    stops: Guard | None = None,
) -> FunctionsInput:
    """The functions to run with: ``given`` (a path or a loaded table, from
    the user), checked against ``named`` ((path, line, SHA-256 or None): the
    file a plan file or a log says its plans were made with). A data file
    never makes htn import Python: if it names a functions file the user
    must give it, and one whose SHA-256 differs is refused."""
    if named is None:
        return given
    path, at, digest = named
    at = line or at
    if given is None:
        raise HtnError(
            f"these plans were made with the functions file {path}; htn imports "
            f"no Python a data file names: give {option} {path} to run it",
            where,
            at,
        )
    if digest and is_path(given):
        # read once: the bytes checked are the bytes that run
        def check(actual: str) -> None:
            if actual != digest:
                raise HtnError(
                    f"{option} {os.fspath(given)} is not the functions file these "
                    f"plans were made with ({path}): its SHA-256 is "
                    f"{actual[:12]}..., recorded {digest[:12]}...",
                    where,
                    at,
                )

        table = FunctionTable(stops) if stops is not None else FunctionTable()
        table.load_file(os.fspath(given), check)
        return table
    return given


@dataclass
class LoggedRun:
    """What a log's header records of its run (``htn run --log``), with the
    plan file it names, read and checked to be unchanged."""

    log: str
    plan: PlanFile
    plan_index: int
    domain: str | None
    problem: str | None
    functions: FunctionsInput  # a path, or the file loaded once checked (its SHA-256)
    robot: str
    seed: int
    faults: str
    retries: dict[str, int]
    replan: bool

    def options(self) -> dict[str, Any]:
        """The keyword arguments of :func:`htn.api.run.run` for the same run."""
        return dict(
            plan=self.plan,
            plan_index=self.plan_index,
            domain=self.domain,
            problem=self.problem,
            functions=self.functions,
            robot=self.robot,
            seed=self.seed,
            faults=self.faults,
            retries=self.retries,
            replan=self.replan,
        )


def read_run_log(
    path: StrPath, functions: FunctionsInput = None, stops: Guard | None = None
) -> LoggedRun:
    """The run a log records (its first event, the header): the plan file it
    ran, its domain and problem must be there and unchanged (their SHA-256),
    else an input error at the log's first line. ``functions``: the user's
    functions file, required if the run had one (the log's is never loaded
    because the log names it) and checked to be that file."""
    log = os.fspath(path)
    rec = read_header(log)
    check_plan_present(rec["plan"], log)
    pf = read_plan_file(rec["plan"])
    check_plan_digest(rec["plan"], rec.get("plan_sha256"), pf.sha256, log)
    for kind in ("domain", "problem"):
        check_unchanged(rec, kind, log)
    named = (rec["functions"], 1, rec.get("functions_sha256")) if rec.get("functions") else None
    functions = checked_functions(named, functions, log, 1, stops=stops)
    return LoggedRun(
        log,
        pf,
        rec["plan_index"],
        rec["domain"],
        rec["problem"],
        functions,
        rec["robot"],
        rec["seed"],
        rec["faults"],
        dict(rec["retries"] or {}),
        rec["replan"],
    )
