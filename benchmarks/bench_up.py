"""Benchmark: htn and Aries through unified-planning, on the same problems, in one run.

The problems are UP's own hierarchical test cases (``up_test_cases``'
``builtin.hierarchical`` and the hierarchical examples of
``unified_planning.test``) and the IPC 2020 total-order HDDL sample in
``../shared/corpus/ipc2020-to`` (``HTN_SHARED`` to move it), read with UP's
HDDL reader (``PDDLReader``). Each engine that supports a problem's kind solves
it through ``OneshotPlanner(name=...)`` with the same timeout; the time is the
wall clock of ``solve`` (what a UP user waits for: UP's kind check, the
engine's conversion, its search, the plan back; for Aries also its server
process and gRPC), the median of ``--repeat`` runs (one when it timed out); ``internal`` is the
engine's own ``engine_internal_time``; ``cpu`` the CPU time of this process
and of the engine's child processes (Aries' server, counted once it has
ended: its threads may add up to more than the wall clock), less sensitive
to a loaded machine. The ratios are htn's over Aries', on the problems both
solved.

Every plan is checked three ways, each letter V (valid), I (invalid) or -:

* ``U``: UP's own validator (``SequentialPlanValidator``) on the plan's
  action sequence: executable from the initial state and reaching the goal,
  in UP's semantics. UP has no validator of its own for hierarchical plans;
* ``H``: the hierarchical plan (actions and decomposition) with the validator
  UP's factory gives for its kind, htn left out: ``aries-val``; where that
  does not support the problem's kind, or gives no answer within
  ``--validate-timeout`` (it has no time limit of its own; its server is
  then killed) or fails (a plan over gRPC's 4 MB message limit), htn's
  (``htn validate``'s replay and the decomposition check of
  :mod:`htn.up.check`). The letter is followed by ``a`` or ``h`` for which one;
* ``F`` (IPC problems): ``htn validate`` of the action sequence against the
  HDDL files as htn's own reader reads them, independent of UP.

Run (pinned to one core, as the README of the corpus measures)::

    taskset -c 1 python benchmarks/bench_up.py                 # 30 s per problem
    python benchmarks/bench_up.py --timeout 10 --repeat 3 --json up.json
    python benchmarks/bench_up.py --htn-search gbfs        # htn's heuristic search
"""

from __future__ import annotations

import gc
import json
import math
import os
import resource
import statistics
import sys
import time
import warnings
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("HTN_SHARED", ROOT.parent / "shared"))
IPC = SHARED / "corpus" / "ipc2020-to"


def up_test_cases() -> list:
    """(name, problem, None) for UP's hierarchical test cases."""
    import unified_planning.test as up_test
    import up_test_cases
    from unified_planning.model.htn import HierarchicalProblem

    sys.path.insert(0, os.path.dirname(up_test_cases.__file__))  # as report.py runs
    import builtin.hierarchical as hierarchical

    cases = {f"up:{k}": v for k, v in hierarchical.get_test_cases().items()}
    cases.update({f"up:{k}": v for k, v in up_test.get_test_cases().items()})
    return [
        (name, tc.problem, None)
        for name, tc in cases.items()
        if isinstance(tc.problem, HierarchicalProblem)
    ]


def ipc_problems() -> list:
    """(name, problem, (domain file, problem file)) for the IPC 2020 sample."""
    from unified_planning.io import PDDLReader

    out = []
    for domain in sorted(IPC.glob("*/domain.hddl")):
        for pf in sorted(domain.parent.glob("*.hddl")):
            if pf.name != "domain.hddl":
                problem = PDDLReader().parse_problem(str(domain), str(pf))
                out.append((f"ipc:{domain.parent.name}/{pf.stem}", problem, (domain, pf)))
    return out


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _reap(patience: float = 5.0) -> None:
    """Wait for the engine's ended child processes (Aries' server is killed
    when its handle is collected), so that their CPU time is counted."""
    deadline = time.perf_counter() + patience
    while time.perf_counter() < deadline:
        try:
            pid, _ = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            time.sleep(0.005)


HTN_PARAMS: dict = {}  # the htn engine's params (--htn-search)


def solve(engine: str, problem, timeout: float, repeat: int) -> dict:
    from unified_planning.shortcuts import OneshotPlanner

    times, cpus, internal, result = [], [], [], None
    params = HTN_PARAMS if engine == "htn" else {}
    for _ in range(repeat):
        cpu0, children0 = time.process_time(), _children_cpu()
        with OneshotPlanner(name=engine, params=params) as planner:
            t0 = time.perf_counter()
            result = planner.solve(problem, timeout=timeout)
            times.append(time.perf_counter() - t0)
        own = time.process_time() - cpu0
        gc.collect()  # ends Aries' server (outside the measured CPU time)
        _reap()
        cpus.append(own + _children_cpu() - children0)
        internal.append(float((result.metrics or {}).get("engine_internal_time", "nan")))
        if result.status.name == "TIMEOUT":
            break  # a repeat would only wait as long again
    plan = result.plan
    return {
        "status": result.status.name,
        "time": statistics.median(times),
        "cpu": statistics.median(cpus),
        "internal": statistics.median(internal),
        "plan": plan,
        "length": len(plan.action_plan.actions) if plan is not None else None,
        "log": [str(m) for m in (result.log_messages or []) if m.message][:3],
    }


def _validate(name: str, problem, plan) -> tuple[str, str]:
    from unified_planning.shortcuts import PlanValidator

    with PlanValidator(name=name) as v:
        res = v.validate(problem, plan)
    return res.status.name, _why(res)


def _aries_val(problem, plan, timeout: float) -> tuple:
    """aries-val's verdict, or (None, why) when it has none within
    ``timeout`` seconds or fails: it has no time limit of its own, so it runs
    in a thread, and its server (a child process of this one) is killed then."""
    import signal
    import threading

    box: dict = {}

    def run():
        try:
            box["answer"] = _validate("aries-val", problem, plan)
        except Exception as e:  # e.g. a plan over gRPC's 4 MB message limit
            box["answer"] = (None, f"failed: {type(e).__name__}: {str(e).splitlines()[0][:200]}")

    before = _aries_servers()
    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(timeout)
    if worker.is_alive():
        for pid in _aries_servers() - before:
            os.kill(pid, signal.SIGKILL)
        worker.join(10)
        return None, f"no answer in {timeout:g} s"
    return box["answer"]


def _aries_servers() -> set:
    """The pids of this process's Aries server children."""
    out = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:
            continue
        name, rest = text[text.index("(") + 1 : text.rindex(")")], text[text.rindex(")") + 2 :]
        if name.startswith("up-aries") and int(rest.split()[1]) == os.getpid():
            out.add(int(stat.parent.name))
    return out


def checks(problem, plan, files, validate_timeout: float = 30.0) -> tuple[str, list]:
    """The check letters of a plan (see the module docstring), and why any said invalid."""
    from unified_planning.engines.plan_validator import SequentialPlanValidator
    from unified_planning.shortcuts import PlanValidator

    notes: list = []
    seq = SequentialPlanValidator()
    seq.skip_checks = True  # it refuses hierarchical kinds; the actions are flat
    res = seq.validate(problem, plan.action_plan)
    letters = "U" + ("V" if res.status.name == "VALID" else "I")
    if letters[-1] == "I":
        notes.append(f"UP: {_why(res)}")
    name = "aries-val"
    with PlanValidator(name="aries-val") as v:
        if not (v.supports(problem.kind) and v.supports_plan(plan.kind)):
            name = "htn"
    status, why = (
        _aries_val(problem, plan, validate_timeout)
        if name == "aries-val"
        else _validate("htn", problem, plan)
    )
    if status is None:  # aries-val gave no answer in time: htn's validator
        notes.append(f"aries-val: {why}")
        name = "htn"
        status, why = _validate("htn", problem, plan)
    letters += " H" + ("V" if status == "VALID" else "I") + name[0]
    if status != "VALID":
        notes.append(f"{name}: {why}")
    if files is not None:
        ok, why = _htn_validate(plan, files)
        letters += " F" + ("V" if ok else "I")
        if not ok:
            notes.append(f"htn validate: {why}")
    return letters, notes


def _why(res) -> str:
    return "; ".join(m.message for m in res.log_messages or []) or res.status.name


def _htn_validate(plan, files) -> tuple[bool, str]:
    from htn.jshop.checks.validate import validate_plan
    from htn.jshop.plans.plan import Plan, Step
    from htn.jshop.readers.load import load_inputs

    domain, problem = load_inputs(str(files[0]), str(files[1]))
    steps = [
        Step(
            "!" + a.action.name.lower(), tuple(x.object().name.lower() for x in a.actual_parameters)
        )
        for a in plan.action_plan.actions
    ]
    verdict = validate_plan(domain, problem.instances[0], Plan(steps, None))
    return verdict.valid, verdict.reason


def engines() -> tuple[list, list]:
    """The engines to compare, and notes on any left out."""
    from unified_planning.shortcuts import get_environment

    import htn.up  # noqa: F401  (registers htn)

    names, notes = ["htn"], []
    try:
        import up_aries  # noqa: F401

        if "aries" in get_environment().factory.engines:
            names.append("aries")
        else:
            notes.append("aries skipped: up_aries imports but is not in UP's factory")
    except ImportError as e:
        notes.append(f"aries skipped: up-aries is not installed ({e}); pip install up-aries")
    return names, notes


@click.command()
@click.option(
    "--timeout", type=float, default=30.0, show_default=True, help="Seconds per engine and problem."
)
@click.option(
    "--repeat",
    type=click.IntRange(min=1),
    default=1,
    show_default=True,
    help="Solve each problem this many times; the median time is shown.",
)
@click.option(
    "--validate-timeout",
    type=float,
    default=20.0,
    show_default=True,
    help="Seconds aries-val may take on one plan (it has no limit of its own); "
    "without its answer the plan's decomposition is checked by htn's validator.",
)
@click.option("--only", default="", help="Problems whose name contains this text.")
@click.option(
    "--json", "json_path", type=click.Path(dir_okay=False), help="Also write the records as JSON."
)
@click.option(
    "--htn-search",
    type=click.Choice(["dfs", "gbfs", "wastar", "auto"]),
    default="dfs",
    show_default=True,
    help="The htn engine's search option.",
)
def main(timeout, repeat, validate_timeout, only, json_path, htn_search):
    """htn and Aries through unified-planning on UP's hierarchical test cases and the IPC sample."""
    HTN_PARAMS["search"] = htn_search
    from unified_planning.shortcuts import get_environment

    get_environment().credits_stream = None
    warnings.simplefilter("ignore")
    names, notes = engines()
    for n in notes:
        print(n)
    problems = up_test_cases() + (ipc_problems() if IPC.is_dir() else [])
    if not IPC.is_dir():
        print(f"IPC sample not found at {IPC} (set HTN_SHARED): UP's test cases only")
    records = []
    print(
        f"| problem | {' | '.join(f'{n} status | {n} s (internal) | {n} cpu s | {n} len | {n} checks' for n in names)}"
        f" | htn/aries s | htn/aries cpu |"
    )
    print("|---" * (3 + 5 * len(names)) + "|")
    for name, problem, files in problems:
        if only and only not in name:
            continue
        row = {"problem": name}
        cells = []
        for engine in names:
            with_engine = _run(engine, problem, files, timeout, repeat, validate_timeout)
            row[engine] = with_engine
            cells.append(_cells(with_engine))
        row["ratio"], row["cpu_ratio"] = _ratio(row, "time"), _ratio(row, "cpu")
        shown = ["-" if x is None else f"{x:.3f}" for x in (row["ratio"], row["cpu_ratio"])]
        print(f"| {name} | {' | '.join(cells)} | {' | '.join(shown)} |", flush=True)
        records.append(row)
    _summary(records, names, timeout)
    if json_path:
        Path(json_path).write_text(json.dumps(records, indent=1, default=str))


def _run(engine, problem, files, timeout, repeat, validate_timeout) -> dict:
    from unified_planning.shortcuts import OneshotPlanner

    with OneshotPlanner(name=engine) as planner:
        if not planner.supports(problem.kind):
            return {"status": "unsupported kind"}
    r = solve(engine, problem, timeout, repeat)
    plan = r.pop("plan")
    r["checks"], r["notes"] = (
        checks(problem, plan, files, validate_timeout) if plan is not None else ("", [])
    )
    return r


def _cells(r: dict) -> str:
    if r["status"] == "unsupported kind":
        return "refused (kind) | - | - | - | -"
    return (
        f"{r['status']} | {r['time']:.3f} ({r['internal']:.3f}) | {r['cpu']:.3f} | "
        f"{r['length'] or '-'} | {r['checks'] or '-'}"
    )


def _verdicts(r: dict) -> dict:
    """Check letter -> True (valid) / False, e.g. {"U": True, "H": False, "F": True}."""
    return {c[0]: c[1] == "V" for c in r.get("checks", "").split()}


def _solved(r: dict) -> bool:
    """A plan came back and UP's own validator accepts its actions."""
    return r.get("status") in ("SOLVED_SATISFICING", "SOLVED_OPTIMALLY") and _verdicts(r).get(
        "U", False
    )


def _ratio(row, what: str):
    if "aries" in row and _solved(row["htn"]) and _solved(row["aries"]):
        return row["htn"][what] / row["aries"][what]
    return None


def _summary(records, names, timeout) -> None:
    print()
    for n in names:
        tried = [r for r in records if r[n]["status"] != "unsupported kind"]
        solved = [r for r in tried if _solved(r[n])]
        valid = [r for r in solved if all(_verdicts(r[n]).values())]
        print(
            f"{n}: solved {len(solved)} of the {len(tried)} problems it supports "
            f"({len(records)} problems, {timeout:g} s each); every check valid on "
            f"{len(valid)}"
        )
    for key, what in (("ratio", "wall-clock time"), ("cpu_ratio", "CPU time")):
        ratios = [r[key] for r in records if r.get(key)]
        if ratios:
            gm = math.exp(sum(math.log(x) for x in ratios) / len(ratios))
            print(
                f"htn/aries {what} on the {len(ratios)} problems both solved: geometric "
                f"mean {gm:.3f}, median {statistics.median(ratios):.3f}"
            )
    for r in records:
        for n in names:
            for note in r[n].get("notes", []):
                print(f"note: {r['problem']} ({n}): {note}")


if __name__ == "__main__":
    main()
