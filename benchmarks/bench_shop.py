"""Benchmark: the partial-order IPC sample through pandaPIparser's SHOP2
translation, planned as JSHOP2 input.

For every instance of ``shared/corpus/ipc-po``, ``pandaPIparser --shop``
writes a JSHOP2-syntax domain and problem (a partially ordered HDDL method
becomes a body with ``(:unordered ...)`` lists). ``htn plan`` plans them as
JSHOP2 input: under the manual's semantics (``:unordered`` interleaves,
manual 3.8; the default), or with ``--jshop2-compat`` (JSHOP2 1.0.3 runs
such bodies in order). Each run has a CPU limit (``RLIMIT_CPU``, 30 s as in
``bench_ipc.py``), and each plan is replayed by ``htn validate`` against
the translation. Prints solved counts per domain beside the HDDL files'
(``bench_ipc.py --sample ipc-po --json`` output, if given)::

    python benchmarks/bench_shop.py
    python benchmarks/bench_shop.py --mode manual --hddl-report po-auto.json
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from collections import Counter
from pathlib import Path

import click

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ipc import SHARED, htn, instances, pandapi, run_limited  # noqa: E402

MODES = {"manual": [], "compat": ["--jshop2-compat"]}


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


def measure(d: Path, p: Path, mode: str, limit: float, pin) -> dict:
    argv = htn("plan", d, p, "-f", "jshop", "--quiet", *MODES[mode])
    run = run_limited(argv, limit, pin)
    row = {"mode": mode, "cpu_s": round(run["cpu_s"], 3)}
    if run["rc"] == 0 and run["stdout"].strip():
        with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as fh:
            fh.write(run["stdout"])
        v = subprocess.run(htn("validate", d, p, fh.name), capture_output=True, text=True)
        Path(fh.name).unlink()
        row["result"] = "plan" if v.returncode == 0 else "plan rejected: " + v.stderr[:200]
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
@click.option("--only", multiple=True, metavar="DOMAIN", help="Only these domain folders.")
@click.option("--limit", default=30.0, show_default=True, help="CPU seconds per run.")
@click.option("--pin", type=int, metavar="CPU", help="Pin every run to this core (taskset).")
@click.option(
    "--hddl-report",
    type=click.Path(dir_okay=False, exists=True),
    help="bench_ipc.py --sample ipc-po --json output, for the HDDL counts.",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def main(modes, only, limit, pin, hddl_report, as_json):
    """Plan the SHOP2 translations of ipc-po as JSHOP2 input; plans replayed."""
    verifier = pandapi()
    if verifier is None:
        raise click.ClickException("needs shared/tools/pandaPIparser (or HTN_PANDAPI)")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (dname, domain, problem) in enumerate(instances(SHARED / "corpus" / "ipc-po", only)):
            out = Path(tmp) / str(k)
            out.mkdir()
            d, p = translate(verifier, domain, problem, out)
            for mode in modes or MODES:
                row = {"domain": dname, "instance": problem.name, **measure(d, p, mode, limit, pin)}
                rows.append(row)
                click.echo(
                    f"{dname} {problem.name} {mode}: {row['result']} {row['cpu_s']:.2f} s CPU",
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
        mode: dict(Counter(r["domain"] for r in rows if r["mode"] == mode and r["solved"]))
        for mode in modes or MODES
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
            f"{r['domain']:28} {r['instance']:40} {r['mode']:7} {r['result'][:40]:40} "
            f"{r['cpu_s']:6.2f}"
            + (f"  HDDL: {'solved' if hddl[(r['domain'], r['instance'])] else '-'}" if hddl else "")
        )
    click.echo(
        "solved: "
        + ", ".join(f"{k} {v} of {len(rows) // len(modes or MODES)}" for k, v in totals.items())
    )


if __name__ == "__main__":
    main()
