"""Benchmark: htn and Aries on the partial-order IPC sample, in one run.

HyperTensioN, the peer of ``bench_ipc.py``'s total-order figures, plans
total order only; Aries (through unified-planning, ``up-aries``) is the
partial-order planner that runs here. For every instance of
``../shared/corpus/ipc-po`` (``HTN_SHARED`` to move it):

* htn: ``htn plan -f ipc --search auto`` under a CPU limit, its plan checked
  by ``htn validate`` and pandaPIparser (``bench_ipc.measure``);
* Aries: the instance read with UP's HDDL reader (``PDDLReader``; what it
  cannot read is reported with its error), solved by
  ``OneshotPlanner(name="aries")`` with the same limit as a wall-clock
  timeout (Aries runs several threads: its CPU time, its server process
  included, is reported beside the wall clock), its plan checked as in
  ``bench_up.py`` (``U``: UP's sequential validator on the actions; ``H``:
  aries-val or htn's validator on the hierarchical plan; ``F``: ``htn
  validate`` of the actions against the HDDL files).

The ratio is htn's CPU time over Aries' (wall clock and CPU), on the
instances both solve::

    python benchmarks/bench_po_aries.py --pin 1           # 30 s per instance
    python benchmarks/bench_po_aries.py --only Transport --limit 60 --json
"""

from __future__ import annotations

import gc
import json
import math
import sys
import warnings
from pathlib import Path

import click

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_ipc  # noqa: E402
import bench_up  # noqa: E402


def aries(domain: Path, problem: Path, limit: float, validate_timeout: float) -> dict:
    from unified_planning.io import PDDLReader

    try:
        up_problem = PDDLReader().parse_problem(str(domain), str(problem))
    except Exception as e:  # UP's reader: its own exceptions, pyparsing's
        first = (str(e).splitlines() or [""])[0][:160]
        return {"status": "UP cannot read", "why": f"{type(e).__name__}: {first}"}
    r = bench_up.solve("aries", up_problem, limit, 1)
    out = {k: r[k] for k in ("status", "time", "cpu", "length")}
    if r["plan"] is None and r["log"]:
        out["why"] = r["log"][0].splitlines()[0][:200]
    if r["plan"] is not None:
        out["checks"], notes = bench_up.checks(
            up_problem, r["plan"], (domain, problem), validate_timeout
        )
        out["valid"] = all(part[1] == "V" for part in out["checks"].split())
        out["notes"] = notes
    gc.collect()
    return out


def _solved(a: dict) -> bool:
    return a.get("valid", False)


def _geomean(xs: list):
    return round(math.exp(sum(map(math.log, xs)) / len(xs)), 3) if xs else None


@click.command()
@click.option("--only", multiple=True, metavar="DOMAIN", help="Only these domain folders.")
@click.option(
    "--limit",
    default=30.0,
    show_default=True,
    help="Seconds per instance: htn's CPU limit, Aries' timeout.",
)
@click.option(
    "--validate-timeout",
    default=20.0,
    show_default=True,
    help="Seconds aries-val may take on one plan (then htn's validator).",
)
@click.option("--pin", type=int, metavar="CPU", help="Pin htn's runs to this core (taskset).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def main(only, limit, validate_timeout, pin, as_json):
    """htn (--search auto) and Aries through unified-planning on ipc-po."""
    from unified_planning.shortcuts import get_environment

    get_environment().credits_stream = None
    warnings.simplefilter("ignore")
    names, notes = bench_up.engines()
    if "aries" not in names:
        raise click.ClickException("; ".join(notes))
    folder = bench_ipc.SHARED / "corpus" / "ipc-po"
    if not folder.is_dir():
        raise click.ClickException(f"no sample at {folder} (set HTN_SHARED)")
    verifier = bench_ipc.pandapi()
    rows = []
    for dname, domain, problem in bench_ipc.instances(folder, only):
        h = bench_ipc.measure(dname, domain, problem, "auto", True, limit, 1, verifier, pin, None)
        a = aries(domain, problem, limit, validate_timeout)
        row = {"domain": dname, "instance": problem.name, "htn": h, "aries": a}
        if h["solved"] and _solved(a):
            row["ratio_wall"] = h["cpu_median_s"] / max(a["time"], 1e-3)
            row["ratio_cpu"] = h["cpu_median_s"] / max(a["cpu"], 1e-3)
        rows.append(row)
        click.echo(
            f"{dname} {problem.name}: htn {'solved' if h['solved'] else h['result']} "
            f"{h['cpu_median_s']:.2f} s CPU; aries {a['status']}"
            + (
                f" {a['time']:.2f} s ({a['cpu']:.2f} s CPU) {a.get('checks', '')}"
                if "time" in a
                else ""
            )
            + (f" ({a['why']})" if "why" in a else ""),
            err=True,
        )
    read = [r for r in rows if r["aries"]["status"] != "UP cannot read"]
    both = [r for r in rows if "ratio_cpu" in r]
    summary = {
        "instances": len(rows),
        "htn_solved": sum(r["htn"]["solved"] for r in rows),
        "up_reads": len(read),
        "htn_solved_of_read": sum(r["htn"]["solved"] for r in read),
        "aries_solved": sum(_solved(r["aries"]) for r in rows),
        "both_solved": len(both),
        "ratio_wall_geomean": _geomean([r["ratio_wall"] for r in both]),
        "ratio_cpu_geomean": _geomean([r["ratio_cpu"] for r in both]),
    }
    if as_json:
        click.echo(
            json.dumps(
                {"limit_s": limit, "summary": summary, "instances": rows}, indent=1, default=str
            )
        )
        return
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"ipc-po: htn --search auto and Aries (UP), {limit:g} s per instance")
    for col in (
        "domain",
        "instance",
        "htn",
        "htn CPU s",
        "aries",
        "aries s",
        "aries CPU s",
        "checks",
        "htn/aries CPU",
    ):
        t.add_column(
            col,
            justify="left" if col in ("domain", "instance", "htn", "aries", "checks") else "right",
        )
    for r in rows:
        h, a = r["htn"], r["aries"]
        t.add_row(
            r["domain"],
            r["instance"],
            "solved" if h["solved"] else h["result"],
            f"{h['cpu_median_s']:.2f}",
            a["status"],
            f"{a['time']:.2f}" if "time" in a else "-",
            f"{a['cpu']:.2f}" if "cpu" in a else "-",
            a.get("checks", "-"),
            f"{r['ratio_cpu']:.3g}" if "ratio_cpu" in r else "-",
        )
    console = Console(width=None if sys.stdout.isatty() else 160)
    console.print(t)
    console.print(summary)


if __name__ == "__main__":
    main()
