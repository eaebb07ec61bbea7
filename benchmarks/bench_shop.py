"""Benchmark: the partial-order IPC sample through pandaPIparser's SHOP2
translation, planned as JSHOP2 input.

For every instance of ``shared/corpus/ipc-po`` (or of ``--folder``, a folder
of HDDL domain folders such as ``partial-order/`` of the IPC 2020 repository,
github.com/panda-planner-dev/ipc2020-domains), ``pandaPIparser --shop``
writes a JSHOP2-syntax domain and problem (a partially ordered HDDL method
becomes a body with ``(:unordered ...)`` lists). ``htn plan`` plans them as
JSHOP2 input with each ``--search`` (default ``dfs``): under the manual's
semantics (``:unordered`` interleaves, manual 3.8; the default), or with
``--jshop2-compat`` (JSHOP2 1.0.3 runs such bodies in order, ``dfs`` only).
Each run has a CPU limit (``RLIMIT_CPU``, 30 s as in ``bench_ipc.py``), and
each plan is checked twice: ``htn validate`` replays it against the
translation, and the competition's verifier (``pandaPIparser --verify``)
checks its IPC text (``-f ipc``: actions and decomposition) against the
original HDDL files, the translation's names mapped back to the HDDL
spelling (it lower-cases them and writes ``-`` for ``_``) and its
artificial root task ``x--top`` taken out, and the problem's ``:goal``
taken out as the translation leaves it out (SHOP2 has no goals: PCP's
translation accepts any interleaving of its two words). A plan counts when
both accept it. Prints solved counts per domain beside the HDDL files' (``bench_ipc.py
--sample ipc-po --json`` output, if given)::

    python benchmarks/bench_shop.py
    python benchmarks/bench_shop.py --mode manual --hddl-report po-auto.json
    python benchmarks/bench_shop.py --mode manual --search auto --search dfs \
        --folder ipc2020-domains/partial-order --only Rover --only PCP
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import click

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ipc import SHARED, htn, instances, pandapi, precompiled, run_limited  # noqa: E402

MODES = {"manual": [], "compat": ["--jshop2-compat"]}
TOKEN = re.compile(r"[^\s()]+")


def translate(verifier: Path, domain: Path, problem: Path, out: Path) -> tuple:
    d, p = out / "domain.jshop", out / "problem.jshop"
    r = subprocess.run(
        [str(verifier), "--shop", str(domain), str(problem), str(d), str(p)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if r.returncode != 0 or not d.is_file():
        raise click.ClickException(f"pandaPIparser --shop failed on {problem}: {r.stderr[-500:]}")
    return d, p


def spelling(*files: Path) -> dict:
    """The translation's spelling of each HDDL name -> the HDDL spelling."""
    out: dict = {}
    for f in files:
        for tok in TOKEN.findall(f.read_text()):
            out.setdefault(tok.lower().replace("_", "-"), tok)
    return out


def to_hddl(ipc: str, names: dict) -> str:
    """An IPC plan of the translation in the HDDL files' names, without the
    translation's root task (``x--top``, whose subtasks become the roots)."""
    body = [ln.split() for ln in ipc.strip().splitlines() if ln not in ("==>", "<==")]
    tops = {p[0]: p[4:] for p in body if len(p) > 3 and p[1] == "x--top" and p[2] == "->"}
    out = ["==>"]
    for parts in body:
        if parts[0] == "root":
            out.append(" ".join(["root", *(x for i in parts[1:] for x in tops.get(i) or [i])]))
        elif parts[0] not in tops:
            out.append(" ".join(names.get(x.lower(), x) for x in parts))
    return "\n".join([*out, "<=="]) + "\n"


def without_goal(text: str) -> str:
    """An HDDL problem without its ``(:goal ...)``."""
    at = text.find("(:goal")
    if at < 0:
        return text
    depth = 0
    for end in range(at, len(text)):
        depth += {"(": 1, ")": -1}.get(text[end], 0)
        if depth == 0:
            return text[:at] + text[end + 1 :]
    return text


def verified(verifier: Path, hddl: tuple, lisp: tuple, ipc: str, plan_file: Path) -> str:
    """ "plan" when htn validate (on the translation) and pandaPIparser (on
    the HDDL files) accept the plan, else what refused it."""
    v = subprocess.run(htn("validate", *lisp, plan_file), capture_output=True, text=True)
    if v.returncode != 0:
        return "plan rejected: " + v.stderr[:200]
    folder = lisp[0].parent
    plan, problem = folder / "plan.ipc", folder / "problem-without-goal.hddl"
    plan.write_text(to_hddl(ipc, spelling(*hddl)))
    problem.write_text(without_goal(hddl[1].read_text()))
    theirs = subprocess.run(
        [str(verifier), "-C", "--verify", str(hddl[0]), str(problem), str(plan)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    if theirs.returncode == 0 and "Plan verification result: true" in theirs.stdout:
        return "plan"
    return "plan rejected by pandaPIparser"


def measure(hddl: tuple, lisp: tuple, mode: str, search: str, limit: float, pin, verifier) -> dict:
    plan_file = lisp[0].parent / "plan.txt"
    plan_file.unlink(missing_ok=True)
    argv = htn(
        "plan", *lisp, "-f", "ipc", "--quiet", "--search", search, "-o", plan_file, *MODES[mode]
    )
    run = run_limited(argv, limit, pin)
    row = {"mode": mode, "search": search, "cpu_s": round(run["cpu_s"], 3)}
    if run["rc"] == 0 and plan_file.is_file():
        row["result"] = verified(verifier, hddl, lisp, run["stdout"], plan_file)
    elif run["rc"] == 1:
        row["result"] = "no plan"
    elif run["rc"] < 0 or run["cpu_s"] >= limit or run["guard"]:
        row["result"] = "CPU limit"
    else:
        row["result"] = "error: " + (run["stderr"].strip().splitlines() or ["?"])[0][:200]
    row["solved"] = row["result"] == "plan"
    return row


@click.command()
@click.option(
    "--mode",
    "modes",
    multiple=True,
    type=click.Choice(list(MODES)),
    help="JSHOP2 semantics [default: both].",
)
@click.option(
    "--search",
    "searches",
    multiple=True,
    default=["dfs"],
    show_default=True,
    help="htn plan --search (repeat for several).",
)
@click.option(
    "--folder",
    type=click.Path(file_okay=False, exists=True, path_type=Path),
    help="A folder of HDDL domain folders [default: shared/corpus/ipc-po].",
)
@click.option("--only", multiple=True, metavar="DOMAIN", help="Only these domain folders.")
@click.option("--limit", default=30.0, show_default=True, help="CPU seconds per run.")
@click.option("--pin", type=int, metavar="CPU", help="Pin every run to this core (taskset).")
@click.option(
    "--hddl-report",
    type=click.Path(dir_okay=False, exists=True),
    help="bench_ipc.py --sample ipc-po --json output, for the HDDL counts.",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def main(modes, searches, folder, only, limit, pin, hddl_report, as_json):
    """Plan the SHOP2 translations of ipc-po as JSHOP2 input; plans verified."""
    verifier = pandapi()
    if verifier is None:
        raise click.ClickException("needs shared/tools/pandaPIparser (or HTN_PANDAPI)")
    rows = []
    runs = [
        (mode, search)
        for mode in modes or MODES
        for search in searches
        if mode == "manual" or search == "dfs"  # --jshop2-compat is depth-first only
    ]
    sample = folder or SHARED / "corpus" / "ipc-po"
    with tempfile.TemporaryDirectory() as tmp, precompiled():
        for k, (dname, domain, problem) in enumerate(instances(sample, only)):
            out = Path(tmp) / str(k)
            out.mkdir()
            lisp = translate(verifier, domain, problem, out)
            for mode, search in runs:
                row = measure((domain, problem), lisp, mode, search, limit, pin, verifier)
                rows.append({"domain": dname, "instance": problem.name, **row})
                click.echo(
                    f"{dname} {problem.name} {mode} {search}: {row['result']} "
                    f"{row['cpu_s']:.2f} s CPU",
                    err=True,
                )
    hddl = {}
    if hddl_report:
        for s in json.loads(Path(hddl_report).read_text())["samples"]:
            if s["summary"]["sample"] != "ipc-po":  # a report of several samples
                continue
            for r in s["instances"]:
                hddl[(r["domain"], r["instance"])] = r["solved"]
    summary = {
        f"{mode} {search}": dict(
            Counter(
                r["domain"]
                for r in rows
                if r["mode"] == mode and r["search"] == search and r["solved"]
            )
        )
        for mode, search in runs
    }
    totals = {mode: sum(c.values()) for mode, c in summary.items()}
    if hddl:
        totals["hddl"] = sum(hddl.values())
    if as_json:
        click.echo(
            json.dumps(
                {"limit_s": limit, "totals": totals, "per_domain": summary, "instances": rows},
                indent=1,
            )
        )
        return
    for r in rows:
        click.echo(
            f"{r['domain']:28} {r['instance']:30} {r['mode']:7} {r['search']:5} {r['result'][:32]:32} "
            f"{r['cpu_s']:6.2f}"
            + (f"  HDDL: {'solved' if hddl[(r['domain'], r['instance'])] else '-'}" if hddl else "")
        )
    click.echo(
        "solved: " + ", ".join(f"{k} {v} of {len(rows) // len(runs)}" for k, v in totals.items())
    )


if __name__ == "__main__":
    main()
