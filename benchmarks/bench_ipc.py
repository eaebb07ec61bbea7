"""Benchmark: the IPC 2020 total-order HDDL sample, beside HyperTensioN.

For every instance of ``shared/corpus/ipc2020-to`` (domain folders with a
``domain.hddl`` and problem files), measures

* the whole ``htn plan DOMAIN PROBLEM -f ipc`` process (parse, plan, print),
  wall time, with the competition's limit (30 s here, as in the folder's
  README), median of ``--runs`` runs;
* the search alone, in-process and cold (the first search of the process,
  like HyperTensioN's own "plan ms"), in CPU time so that other work on the
  machine does not count, and the plan's length; beside it (``init_ms``,
  JSON only) the planner's set-up before the search (building its state and
  tables);
* whether the plan is valid (replayed from the initial state, goal checked).

and prints them beside HyperTensioN's figures from the folder's README, with
solved counts and time ratios (ours / HyperTensioN; geometric means)::

    python benchmarks/bench_ipc.py
    python benchmarks/bench_ipc.py --only Towers --runs 3
    python benchmarks/bench_ipc.py --json
"""
from __future__ import annotations

import json
import math
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_CORPUS = ROOT.parent / "shared" / "corpus" / "ipc2020-to"


def reference(corpus: Path) -> dict:
    """HyperTensioN's figures: (domain, instance) -> row of the README table."""
    rows = {}
    for line in (corpus / "README.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 6 and cells[2] in ("yes", "no"):
            domain, inst, solved, proc, plan_ms, length = cells
            rows[(domain, inst)] = {"solved": solved == "yes", "process_s": float(proc),
                                    "plan_ms": float(plan_ms), "length": int(length)}
    return rows


def instances(corpus: Path, only) -> list:
    out = []
    for folder in sorted(p for p in corpus.iterdir() if (p / "domain.hddl").is_file()):
        if only and folder.name not in only:
            continue
        for problem in sorted(folder.glob("*.hddl")):
            if problem.name != "domain.hddl":
                out.append((folder.name, problem.stem, folder / "domain.hddl", problem))
    return out


def process_time(domain: Path, problem: Path, limit: float) -> tuple[float, bool]:
    t = time.perf_counter()
    try:
        r = subprocess.run([sys.executable, "-m", "htn", "plan", str(domain), str(problem),
                            "-f", "ipc", "--quiet"], capture_output=True, text=True,
                           timeout=limit, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return limit, False
    return time.perf_counter() - t, r.returncode == 0 and r.stdout.startswith("==>")


def search(domain: Path, problem: Path, limit: float) -> dict:
    from htn.jshop import Planner, load_domain, load_problem
    from htn.jshop.plans.validate import validate_plan
    dom = load_domain(str(domain))
    inst = load_problem(str(problem)).instances[0]
    start = time.process_time()
    planner = Planner(dom, inst)
    cpu = time.process_time()
    plan = next(planner.plans(timeout=limit), None)
    init, cpu = cpu - start, time.process_time() - cpu
    valid = plan is not None and validate_plan(dom, inst, plan).valid
    return {"search_ms": cpu * 1000, "init_ms": init * 1000, "length": len(plan) if plan else None,
            "valid": valid, "timed_out": planner.stats.timed_out}


def _geomean(xs: list) -> float:
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


@click.command()
@click.option("--corpus", type=click.Path(file_okay=False), default=str(DEFAULT_CORPUS),
              show_default=True, help="The shared/corpus/ipc2020-to folder.")
@click.option("--only", multiple=True, help="Run only these domains (repeatable).")
@click.option("--limit", default=30.0, show_default=True, help="Seconds per instance.")
@click.option("--runs", default=1, show_default=True, help="Whole-process runs per instance.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def main(corpus, only, limit, runs, as_json):
    """Solve the IPC 2020 sample with a time limit, beside HyperTensioN's figures."""
    corpus = Path(corpus)
    if not (corpus / "README.md").is_file():
        raise click.ClickException(f"no IPC sample at {corpus}")
    ref = reference(corpus)
    rows = []
    for dname, inst, domain, problem in instances(corpus, only):
        times, ok = [], True
        for _ in range(runs):
            t, solved = process_time(domain, problem, limit)
            times.append(t)
            ok &= solved
        s = search(domain, problem, limit)
        h = ref.get((dname, re.sub(r"\.hddl$", "", inst)), {})
        row = {"domain": dname, "instance": inst, "solved": ok and s["valid"],
               "process_s": round(statistics.median(times), 3),
               "search_ms": round(s["search_ms"], 2), "init_ms": round(s["init_ms"], 2),
               "length": s["length"],
               "ht_solved": h.get("solved"), "ht_process_s": h.get("process_s"),
               "ht_plan_ms": h.get("plan_ms"), "ht_length": h.get("length")}
        if row["solved"] and h.get("solved"):
            row["process_ratio"] = round(row["process_s"] / h["process_s"], 2)
            row["search_ratio"] = round(row["search_ms"] / h["plan_ms"], 2)
        rows.append(row)
        if not as_json:
            click.echo(f"{dname} {inst}: {'solved' if row['solved'] else 'NOT solved'} "
                       f"{row['process_s']:.2f} s, search {row['search_ms']:.1f} ms", err=True)
    summary = {
        "instances": len(rows),
        "solved": sum(r["solved"] for r in rows),
        "hypertension_solved": sum(bool(r["ht_solved"]) for r in rows),
        "process_ratio_geomean": round(_geomean([r["process_ratio"] for r in rows
                                                 if "process_ratio" in r]), 2),
        "search_ratio_geomean": round(_geomean([r["search_ratio"] for r in rows
                                                if "search_ratio" in r]), 2),
        "limit_s": limit,
    }
    if as_json:
        click.echo(json.dumps({"instances": rows, "summary": summary}, indent=1))
        return
    from rich.console import Console
    from rich.table import Table
    t = Table(title=f"IPC 2020 total-order sample, {limit:g} s limit: htn vs HyperTensioN")
    for col in ("domain", "instance", "solved", "process s", "HT process s", "ratio",
                "search ms", "HT plan ms", "ratio ", "length", "HT length"):
        t.add_column(col, justify="left" if col in ("domain", "instance") else "right")
    for r in rows:
        t.add_row(r["domain"], r["instance"], "yes" if r["solved"] else "[red]no[/red]",
                  f"{r['process_s']:.2f}", _fmt(r["ht_process_s"]),
                  _fmt(r.get("process_ratio")), f"{r['search_ms']:.1f}", _fmt(r["ht_plan_ms"]),
                  _fmt(r.get("search_ratio")), _fmt(r["length"]), _fmt(r["ht_length"]))
    Console().print(t)
    Console().print(f"solved {summary['solved']} of {summary['instances']} "
                    f"(HyperTensioN {summary['hypertension_solved']}); geometric mean of "
                    f"ratios ours/HyperTensioN: process {summary['process_ratio_geomean']}, "
                    f"search {summary['search_ratio_geomean']}")


def _fmt(x) -> str:
    if x is None:
        return "-"
    return f"{x:g}" if isinstance(x, float) else str(x)


if __name__ == "__main__":
    main()
