"""Benchmark: the IPC HDDL samples under the competition's limit, every plan verified.

For every instance of the shared samples ``ipc2020-to``, ``ipc2020-to-hard``,
``ipc2023-to`` and ``ipc-po`` (domain folders under ``shared/corpus``), runs

* ``htn plan DOMAIN PROBLEM -f ipc [--search S]`` as a process under a CPU
  limit (``RLIMIT_CPU``, 30 s as at the competition), and takes its CPU time
  (user + system, from ``wait4``): median and max over ``--runs`` runs;
* checks the plan it printed twice: ``htn validate`` (actions, decomposition,
  goal) and the competition's verifier, pandaPIparser ``--verify``, when
  ``shared/tools/pandaPIparser`` is there (or ``HTN_PANDAPI``). An instance
  counts as solved only when every check that ran accepted its plan;
* for ``ipc2020-to``, the search alone beside HyperTensioN's "plan ms" from
  that folder's README: with ``--search dfs`` the CPU time of the first
  search in a fresh process (``Planner.plans``, the public API), otherwise
  the ``search_ms`` that ``htn plan -f json --search S`` reports.

With ``--hypertension DIR`` (a copy of github.com/Maumagnaguagno/HyperTensioN;
``ruby`` on the PATH) HyperTensioN runs beside htn on every instance, as at
the IPC (``ruby --disable=all Hype.rb DOMAIN PROBLEM typredicate pullup dejavu
run``, ``RUBY_THREAD_VM_STACK_SIZE=536870912``), under the same CPU limit,
which of the two goes first alternating from one instance to the next; the
report adds both planners' whole-process CPU time (user + system) and htn's
over HyperTensioN's on the instances both solve (geometric mean, the worst,
how many over 4). htn's bytecode is compiled before the first run, as pip
does when it installs a package: a run never pays for compiling htn's
modules (``PYTHONDONTWRITEBYTECODE`` would otherwise make every run do so).

``--search`` is passed through to ``htn plan --search``; an ``htn`` without
that option runs ``dfs`` (its only search) without the flag, and reports the
other searches as not available. Per sample it prints solved, median and max
CPU time (of the solved instances), and for ``ipc2020-to`` the ratios::

    python benchmarks/bench_ipc.py                      # all four samples, dfs
    python benchmarks/bench_ipc.py --sample ipc2020-to --runs 3
    python benchmarks/bench_ipc.py --search gbfs --json
    python benchmarks/bench_ipc.py --sample ipc2020-to --sample ipc2020-to-slow \
        --hypertension ~/HyperTensioN --runs 3 --pin 1
    python benchmarks/bench_ipc.py --folder ipc2020-domains/total-order \
        --per-domain 8 --search auto --pin 0   # 192 of IPC 2020's instances

``--folder`` measures any folder of domain folders laid out like the samples
(the competition's repository, github.com/panda-planner-dev/ipc2020-domains),
``--per-domain N`` N problems of each, evenly spaced from the first to the
last in natural order. pandaPIparser may take longer than the plan on plans of
100k actions; after ``--verify-limit`` seconds (600) its check is left out
(``pandapi_unfinished``) and ``htn validate``'s decides.
"""

from __future__ import annotations

import json
import math
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

import click

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("HTN_SHARED", ROOT.parent / "shared"))
SAMPLES = ("ipc2020-to", "ipc2020-to-slow", "ipc2020-to-hard", "ipc2023-to", "ipc-po")
SEARCHES = ("dfs", "gbfs", "auto")
WALL_GUARD = 40
VERIFY_LIMIT = 600  # seconds pandaPIparser may take on one plan (Towers pfile_15: more)
MEASURED: list = []  # the instances measured so far (who goes first alternates)

# the search alone, in a fresh process (dfs: the planner's public API)
SEARCH_CPU = """
import json, sys, time
from htn.jshop import Planner
from htn.jshop.readers.load import load_inputs
dom, prob = load_inputs(sys.argv[1], sys.argv[2])
start = time.process_time()
planner = Planner(dom, prob.instances[0])
t = time.process_time()
plan = next(planner.plans(), None)
print(json.dumps({"search_ms": (time.process_time() - t) * 1000, "init_ms": (t - start) * 1000,
                  "found": plan is not None}))
"""


def instances(sample: Path, only, per_domain: int | None = None) -> list:
    """(domain folder, domain file, problem file) of each instance: the
    folder's ``domain.hddl`` (or its one other ``*domain*.hddl``), or the
    problem's own ``<problem>-domain.hddl`` where each has one. With
    ``per_domain``, that many problems of each folder, evenly spaced in
    natural order from the first to the last."""
    out = []
    for folder in sorted(p for p in sample.iterdir() if p.is_dir()):
        if only and folder.name not in only:
            continue
        files = sorted((p for p in folder.iterdir() if p.suffix in (".hddl", ".pddl")), key=natural)
        domains = [f for f in files if "domain" in f.name.lower()]
        problems = [f for f in files if f not in domains]
        if per_domain is not None and len(problems) > per_domain:
            last = len(problems) - 1
            picks = sorted({round(i * last / max(1, per_domain - 1)) for i in range(per_domain)})
            problems = [problems[k] for k in picks]
        for problem in problems:
            stem = problem.name.rsplit(".", 1)[0]
            own = [d for d in domains if d.name == f"{stem}-domain.hddl"]
            if own or domains:
                out.append((folder.name, (own or domains)[0], problem))
    return out


def natural(path: Path) -> list:
    """A sort key: the name's digit runs compared as numbers (p2 before p10)."""
    return [int(x) if x.isdigit() else x for x in re.split(r"(\d+)", path.name)]


def hypertension(sample: Path) -> dict:
    """HyperTensioN's "plan ms" per (domain, instance) from ipc2020-to's README."""
    rows = {}
    readme = sample / "README.md"
    for line in readme.read_text().splitlines() if readme.is_file() else []:
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 6 and cells[2] in ("yes", "no"):
            rows[(cells[0], cells[1])] = float(cells[4]) if cells[2] == "yes" else None
    return rows


def run_limited(argv: list, limit: float, pin=None, cwd=ROOT, env=None) -> dict:
    """Run ``argv`` under ``RLIMIT_CPU`` = ``limit`` s; its CPU time, exit
    status (negative: the signal), stdout and stderr. A wall-clock guard
    (``WALL_GUARD`` times the limit: the machine may be shared) kills a
    process that waits instead of computing."""
    if pin is not None:
        argv = ["taskset", "-c", str(pin), *argv]
    soft = max(1, math.ceil(limit))

    def cap():
        resource.setrlimit(resource.RLIMIT_CPU, (soft, soft + 1))

    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(
            argv, stdout=out, stderr=err, cwd=cwd, env=env, preexec_fn=cap, text=True
        )
        fired: list = []

        def kill():
            fired.append(True)
            proc.kill()

        guard = threading.Timer(WALL_GUARD * limit, kill)
        guard.start()
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            guard.cancel()
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        return {
            "cpu_s": usage.ru_utime + usage.ru_stime,
            "rc": proc.returncode,
            "stdout": out.read(),
            "stderr": err.read(),
            "guard": bool(fired),
        }


def run_hypertension(ht: Path, domain: Path, problem: Path, limit: float, pin) -> dict:
    """HyperTensioN on one instance, as at the IPC: its CPU time and whether
    it printed a plan."""
    env = {**os.environ, "RUBY_THREAD_VM_STACK_SIZE": "536870912"}
    argv = ["ruby", "--disable=all", "Hype.rb", str(domain), str(problem)]
    r = run_limited([*argv, "typredicate", "pullup", "dejavu", "run"], limit, pin, ht, env)
    r["solved"] = r["rc"] == 0 and "-Plan-" in r["stdout"]
    return r


@contextmanager
def precompiled():
    """htn's modules with their bytecode beside them, as pip writes it at
    install, while the block runs; the ``__pycache__`` folders made here are
    removed after it (a wheel built from the checkout would take them in).
    A cache folder of their own (``PYTHONPYCACHEPREFIX``) would leave every
    other module without bytecode."""
    import compileall
    import shutil

    import htn as package

    root = Path(package.__file__).parent
    before = set(root.rglob("__pycache__"))
    compileall.compile_dir(root, quiet=1, workers=1)
    try:
        yield
    finally:
        for folder in set(root.rglob("__pycache__")) - before:
            shutil.rmtree(folder, ignore_errors=True)


def htn(*args) -> list:
    return [sys.executable, "-m", "htn", *map(str, args)]


def has_search_option() -> bool:
    r = subprocess.run(htn("plan", "--help"), capture_output=True, text=True, cwd=ROOT)
    return "--search" in r.stdout


def editable_install() -> bool:
    """Whether htn is installed editable (``pip install -e``): its import hook
    then runs in every process, about 12 ms of CPU before htn's first line
    (``python -c pass`` in such a virtualenv: 23 ms, against 11 ms after
    ``pip install .``), which a small instance's figure would count."""
    from importlib.metadata import distributions

    for dist in distributions(name="htn"):  # the checkout's htn.egg-info has no direct_url
        text = dist.read_text("direct_url.json")
        if text:
            return bool(json.loads(text).get("dir_info", {}).get("editable"))
    return False


def pandapi() -> Path | None:
    path = Path(os.environ.get("HTN_PANDAPI", SHARED / "tools" / "pandaPIparser" / "pandaPIparser"))
    return path if path.is_file() else None


def verify(domain: Path, problem: Path, text: str, verifier) -> dict:
    """``htn validate`` and pandaPIparser (if any) on an IPC plan text."""
    with tempfile.NamedTemporaryFile("w", suffix=".plan", delete=False) as fh:
        fh.write(text)
    try:
        ours = subprocess.run(
            htn("validate", domain, problem, fh.name), capture_output=True, text=True, cwd=ROOT
        )
        out = {
            "htn_validate": ours.returncode == 0,
            "htn_validate_message": (ours.stderr.splitlines() or [""])[0],
        }
        if verifier is not None:
            try:
                theirs = subprocess.run(
                    [str(verifier), "-C", "--verify", str(domain), str(problem), fh.name],
                    capture_output=True,
                    text=True,
                    timeout=VERIFY_LIMIT,
                )
            except subprocess.TimeoutExpired:  # a plan of 100k actions: htn validate decides
                out["pandapi_unfinished"] = True
                return out
            out["pandapi"] = (
                theirs.returncode == 0 and "Plan verification result: true" in theirs.stdout
            )
        return out
    finally:
        os.unlink(fh.name)


def outcome(run: dict, limit: float) -> str:
    if run["rc"] == 0 and run["stdout"].startswith("==>"):
        return "plan"
    if run.get("guard"):
        return f"killed by the wall-clock guard ({WALL_GUARD:g} x the limit)"
    if run["rc"] < 0 or run["cpu_s"] >= limit:
        return "CPU limit"
    if run["rc"] == 1:
        return "timed out" if "timed out" in run["stderr"] else "no plan"
    first = (run["stderr"].strip().splitlines() or [f"exit {run['rc']}"])[0]
    return f"error: {first[:160]}"


def measure(dname, domain, problem, search, flag, limit, runs, verifier, pin, ref, ht) -> dict:
    argv = htn(
        "plan", domain, problem, "-f", "ipc", "--quiet", *(["--search", search] if flag else [])
    )
    done, theirs = [], []
    for k in range(runs):  # HyperTensioN first on every other instance and run
        if ht is not None and (k + len(MEASURED)) % 2 == 0:
            theirs.append(run_hypertension(ht, domain, problem, limit, pin))
        done.append(run_limited(argv, limit, pin))
        if ht is not None and len(theirs) <= k:
            theirs.append(run_hypertension(ht, domain, problem, limit, pin))
    MEASURED.append(problem)
    first = done[0]
    cpus = [r["cpu_s"] for r in done]
    row = {
        "domain": dname,
        "instance": problem.name,
        "result": outcome(first, limit),
        "cpu_median_s": round(statistics.median(cpus), 3),
        "cpu_max_s": round(max(cpus), 3),
    }
    if row["result"] == "plan":
        row["actions"] = sum(
            1
            for line in first["stdout"].splitlines()[1:]
            if line[:1].isdigit() and " -> " not in line
        )
        row.update(verify(domain, problem, first["stdout"], verifier))
    row["solved"] = row["result"] == "plan" and row["htn_validate"] and row.get("pandapi", True)
    if theirs:
        row["ht_cpu_median_s"] = round(statistics.median(r["cpu_s"] for r in theirs), 3)
        row["ht_solved"] = all(r["solved"] for r in theirs)
        if row["solved"] and row["ht_solved"]:
            row["cpu_ratio"] = round(
                statistics.median(r["cpu_s"] for r in done) / row["ht_cpu_median_s"], 2
            )
    if ref is not None and row["solved"]:
        row["search_ms"] = search_time(domain, problem, search, flag, limit, runs, pin)
        row["ht_plan_ms"] = ht = ref.get((dname, problem.stem))
        if ht:
            row["search_ratio"] = float(f"{row['search_ms'] / ht:.3g}")
    return row


def search_time(domain, problem, search, flag, limit, runs, pin) -> float:
    times = []
    for _ in range(runs):
        if search == "dfs":
            r = run_limited(
                [sys.executable, "-c", SEARCH_CPU, str(domain), str(problem)], limit, pin
            )
            times.append(json.loads(r["stdout"])["search_ms"])
        else:
            r = run_limited(
                htn(
                    "plan",
                    domain,
                    problem,
                    "-f",
                    "json",
                    "--quiet",
                    *(["--search", search] if flag else []),
                ),
                limit,
                pin,
            )
            times.append(json.loads(r["stdout"].splitlines()[-1])["search_ms"])
    return round(statistics.median(times), 2)


def summary(rows: list, sample: str) -> dict:
    solved = [r for r in rows if r["solved"]]
    cpus = [r["cpu_median_s"] for r in solved]
    out = {
        "sample": sample,
        "instances": len(rows),
        "solved": len(solved),
        "plan_rejected": sum(r["result"] == "plan" and not r["solved"] for r in rows),
        "pandapi_unfinished": sum(r.get("pandapi_unfinished", False) for r in rows),
        "cpu_median_s": round(statistics.median(cpus), 3) if cpus else None,
        "cpu_max_s": round(max(cpus), 3) if cpus else None,
    }
    both = [r for r in rows if "cpu_ratio" in r]
    if both:
        worst = max(both, key=lambda r: r["cpu_ratio"])
        out["ht_solved"] = sum(r.get("ht_solved", False) for r in rows)
        out["cpu_ratio_geomean"] = round(
            math.exp(sum(math.log(r["cpu_ratio"]) for r in both) / len(both)), 2
        )
        out["cpu_ratio_worst"] = f"{worst['cpu_ratio']} ({worst['domain']} {worst['instance']})"
        out["cpu_ratio_over_4"] = sum(r["cpu_ratio"] > 4 for r in both)
        out["htn_cpu_median_s"] = round(statistics.median(r["cpu_median_s"] for r in both), 3)
    ratios = [r["search_ratio"] for r in rows if "search_ratio" in r]
    if ratios:
        slow = [r["search_ratio"] for r in rows if "search_ratio" in r and r["ht_plan_ms"] > 10]
        # from the unrounded times: a search of a few µs rounds its ratio to 0
        exact = [max(r["search_ms"], 1e-3) / r["ht_plan_ms"] for r in rows if "search_ratio" in r]
        out["search_ratio_geomean"] = round(math.exp(sum(map(math.log, exact)) / len(exact)), 3)
        out["search_ratio_max"] = max(ratios)
        out["over_10ms_at_most_1"] = f"{sum(x <= 1.0 for x in slow)} of {len(slow)}"
    return out


@click.command()
@click.option(
    "--sample",
    "samples",
    multiple=True,
    type=click.Choice(SAMPLES),
    help="Run only these samples (repeatable) [default: all four].",
)
@click.option(
    "--search",
    type=click.Choice(SEARCHES),
    default="dfs",
    show_default=True,
    help="Passed to 'htn plan --search'.",
)
@click.option(
    "--folder",
    type=click.Path(file_okay=False, exists=True, path_type=Path),
    metavar="DIR",
    help="Measure this folder of domain folders (such as the IPC 2020 repository's "
    "total-order/) instead of the samples.",
)
@click.option(
    "--per-domain",
    type=click.IntRange(min=1),
    metavar="N",
    help="Only N problems per domain folder, evenly spaced in natural order.",
)
@click.option(
    "--verify-limit",
    default=VERIFY_LIMIT,
    show_default=True,
    metavar="SECONDS",
    help="Wall-clock seconds pandaPIparser may take on one plan; beyond, htn validate decides.",
)
@click.option("--only", multiple=True, metavar="DOMAIN", help="Only these domain folders.")
@click.option("--limit", default=30.0, show_default=True, help="CPU seconds per run.")
@click.option(
    "--runs",
    default=1,
    show_default=True,
    type=click.IntRange(min=1),
    help="Runs per instance (median and max CPU time).",
)
@click.option("--pin", type=int, metavar="CPU", help="Pin every run to this core (taskset).")
@click.option(
    "--hypertension",
    "ht",
    type=click.Path(file_okay=False, exists=True, path_type=Path),
    metavar="DIR",
    help="A HyperTensioN checkout (Hype.rb) to run beside htn on every instance.",
)
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of tables.")
def main(samples, search, folder, per_domain, verify_limit, only, limit, runs, pin, ht, as_json):
    """Solve the IPC samples under a CPU limit; every plan verified twice."""
    if ht is not None and not (ht / "Hype.rb").is_file():
        raise click.ClickException(f"{ht}: no Hype.rb (a HyperTensioN checkout?)")
    global VERIFY_LIMIT
    VERIFY_LIMIT = verify_limit
    with precompiled():
        _run(samples, search, folder, per_domain, only, limit, runs, pin, ht, as_json)


def _run(samples, search, folder, per_domain, only, limit, runs, pin, ht, as_json) -> None:
    flag = has_search_option()
    if not flag and search != "dfs":
        message = (
            f"--search {search}: not available (this htn plan has no --search option; "
            "its only search is dfs)"
        )
        click.echo(
            json.dumps({"search": search, "available": False, "message": message})
            if as_json
            else message
        )
        return
    verifier = pandapi()
    editable = editable_install()
    if editable:
        click.echo(
            "note: htn is installed editable (pip install -e); its import hook adds about "
            "12 ms of CPU to every run: measure with 'pip install .' for the figures users see",
            err=True,
        )
    report = {
        "search": search,
        "editable_install": editable,
        "limit_s": limit,
        "runs": runs,
        "pandapiparser": str(verifier) if verifier else None,
        "samples": [],
    }
    folders = [(folder.name, folder)] if folder is not None else []
    for name in samples or (() if folders else SAMPLES):
        folders.append((name, SHARED / "corpus" / name))
    for name, where in folders:
        if not where.is_dir():
            raise click.ClickException(f"no sample at {where} (set HTN_SHARED)")
        ref = hypertension(where) if name == "ipc2020-to" else None
        rows = []
        for dname, domain, problem in instances(where, only, per_domain):
            row = measure(dname, domain, problem, search, flag, limit, runs, verifier, pin, ref, ht)
            rows.append(row)
            click.echo(
                f"{name} {dname} {problem.name}: "  # progress
                f"{'solved' if row['solved'] else row['result']} "
                f"{row['cpu_median_s']:.2f} s CPU"
                + (f", HyperTensioN {row['ht_cpu_median_s']:.2f} s" if ht else ""),
                err=True,
            )
        report["samples"].append({"summary": summary(rows, name), "instances": rows})
    if as_json:
        click.echo(json.dumps(report, indent=1))
    else:
        _print(report)


def _print(report: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console(width=None if sys.stdout.isatty() else 120)
    checks = "htn validate" + (" + pandaPIparser" if report["pandapiparser"] else "")
    t = Table(
        title=f"IPC samples, --search {report['search']}, {report['limit_s']:g} s CPU "
        f"per run; plans checked by {checks}"
    )
    for col in (
        "sample",
        "instances",
        "solved",
        "plan rejected",
        "CPU s median",
        "CPU s max",
        "search/HT geo. mean, max",
        "HT > 10 ms: ratio <= 1",
    ):
        t.add_column(col, justify="left" if col == "sample" else "right")
    for s in report["samples"]:
        m = s["summary"]
        ratio = (
            f"{m['search_ratio_geomean']}, {m['search_ratio_max']}"
            if "search_ratio_geomean" in m
            else "-"
        )
        t.add_row(
            m["sample"],
            str(m["instances"]),
            str(m["solved"]),
            str(m["plan_rejected"]),
            _fmt(m["cpu_median_s"]),
            _fmt(m["cpu_max_s"]),
            ratio,
            m.get("over_10ms_at_most_1", "-"),
        )
    console.print(t)
    for s in report["samples"]:
        m = s["summary"]
        if "cpu_ratio_geomean" in m:
            console.print(
                f"{m['sample']}: HyperTensioN solves {m['ht_solved']} of {m['instances']}; "
                f"htn/HyperTensioN whole-process CPU on the instances both solve: geometric "
                f"mean {m['cpu_ratio_geomean']}, worst {m['cpu_ratio_worst']}, "
                f"{m['cpu_ratio_over_4']} over 4; htn's median {m['htn_cpu_median_s']} s"
            )
    for s in report["samples"]:
        d = Table(title=s["summary"]["sample"])
        cols = ("domain", "instance", "result", "CPU s", "HT CPU s", "CPU ratio")
        for col in (*cols, "search ms", "HT plan ms", "ratio"):
            d.add_column(
                col, justify="left" if col in ("domain", "instance", "result") else "right"
            )
        for r in s["instances"]:
            result = (
                "solved"
                if r["solved"]
                else ("[red]plan rejected[/red]" if r["result"] == "plan" else r["result"])
            )
            d.add_row(
                r["domain"],
                r["instance"],
                result,
                f"{r['cpu_median_s']:.2f}",
                _fmt(r.get("ht_cpu_median_s")),
                _fmt(r.get("cpu_ratio")),
                _fmt(r.get("search_ms")),
                _fmt(r.get("ht_plan_ms")),
                _fmt(r.get("search_ratio")),
            )
        console.print(d)


def _fmt(x) -> str:
    return "-" if x is None else (f"{x:g}" if isinstance(x, float) else str(x))


if __name__ == "__main__":
    main()
