"""Benchmark: what a small HDDL instance costs, whole process, and where it goes.

By default htn is measured as a user installs it: ``pip install`` of this
checkout (not editable) into a new virtualenv with htn's core dependencies
only (``--here`` measures this interpreter's htn instead, whose site may hold
many packages and an editable install's import hook, both slower to start).
Each figure is the CPU time (user + system, from ``wait4``) of a fresh
process, median of ``--runs``: the interpreter alone (``python -c pass``),
``htn --help``, ``htn plan --help``, and ``htn plan DOMAIN PROBLEM -f ipc`` on
small instances (Towers pfile_05 and Childsnack p05 of the shared IPC 2020
sample, and the bundled JSHOP2 domestic problem). Every run is cold: a new
process, nothing kept from an earlier run but htn's bytecode, which is
compiled first, as pip compiles it when it installs htn. Then
``python -X importtime`` of the Towers run lists the modules that cost most
to import (their own time, in ms, as importtime reports it) and cProfile the
top functions by cumulative time. Run::

    python benchmarks/bench_startup.py             # a new virtualenv, 9 runs each
    python benchmarks/bench_startup.py --runs 21 --pin 1
    python benchmarks/bench_startup.py --here      # this interpreter's htn
    python benchmarks/bench_startup.py --json

Target (issue 38): a small HDDL instance in at most 0.06 s of CPU.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

import click

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_ipc import precompiled, run_limited  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("HTN_SHARED", ROOT.parent / "shared"))
IPC = SHARED / "corpus" / "ipc2020-to"


def fresh_venv(folder: Path) -> str:
    """A new virtualenv with this checkout installed by pip; its python."""
    subprocess.run([sys.executable, "-m", "venv", str(folder)], check=True)
    py = str(folder / "bin" / "python")
    subprocess.run(
        [py, "-m", "pip", "install", "-q", str(ROOT)], check=True, stderr=subprocess.DEVNULL
    )
    return py


def cases(py: str) -> dict[str, list[str]]:
    out = {
        "python -c pass": [py, "-c", "pass"],
        "htn --help": [py, "-m", "htn", "--help"],
        "htn plan --help": [py, "-m", "htn", "plan", "--help"],
        "htn plan domestic bring_object (JSHOP2)": [
            *(py, "-m", "htn", "plan"),
            str(ROOT / "domains" / "domestic.jshop"),
            str(ROOT / "problems" / "bring_object.jshop"),
        ],
    }
    for name, domain, problem in (
        ("Towers pfile_05", "Towers/domain.hddl", "Towers/pfile_05.hddl"),
        ("Childsnack p05", "Childsnack/domain.hddl", "Childsnack/p05.hddl"),
    ):
        if (IPC / domain).is_file():
            out[f"htn plan {name} -f ipc"] = [
                *(py, "-m", "htn", "plan", str(IPC / domain), str(IPC / problem), "-f", "ipc"),
            ]
    return out


def cpu(argv: list[str], pin: int | None) -> float:
    r = run_limited(argv, 60, pin)
    if r["rc"] != 0:
        raise click.ClickException(f"{' '.join(argv)} failed: {r['stderr'][-300:]}")
    return float(r["cpu_s"])


def imports(argv: list[str], top: int) -> list[tuple[str, float]]:
    r = subprocess.run([argv[0], "-X", "importtime", *argv[1:]], capture_output=True, text=True)
    own = []
    for line in r.stderr.splitlines():
        if line.startswith("import time:") and "|" in line:
            parts = [p.strip() for p in line[len("import time:") :].split("|")]
            if parts[0].isdigit():
                own.append((parts[2].strip(), int(parts[0]) / 1000))
    return sorted(own, key=lambda x: -x[1])[:top]


@click.command()
@click.option("--runs", default=9, show_default=True, type=click.IntRange(min=1))
@click.option("--pin", type=int, metavar="CPU", help="Pin every run to this core (taskset).")
@click.option("--top", default=15, show_default=True, help="Modules listed by import time.")
@click.option("--here", is_flag=True, help="Measure this interpreter's htn, not a new install.")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
def main(runs, pin, top, here, as_json):
    """Whole-process CPU time of htn on small instances, cold."""
    import tempfile
    from contextlib import ExitStack

    with tempfile.TemporaryDirectory() as tmp, ExitStack() as stack:
        if here:  # with its bytecode, as bench_ipc.py measures it
            stack.enter_context(precompiled())
            py = sys.executable
        else:
            click.echo("installing htn into a new virtualenv ...", err=True)
            py = fresh_venv(Path(tmp) / "venv")
        report = measure(py, runs, pin, top)
        report["installed"] = "this interpreter" if here else "a new virtualenv (pip install .)"
    if as_json:
        click.echo(json.dumps(report, indent=1))
        return
    show(report)


def measure(py: str, runs: int, pin: int | None, top: int) -> dict:
    figures = {}
    for name, argv in cases(py).items():
        times = [cpu(argv, pin) for _ in range(runs)]
        figures[name] = {"median_s": round(statistics.median(times), 4), "min_s": min(times)}
        click.echo(f"{name}: {figures[name]['median_s']:.3f} s", err=True)
    towers = [a for n, a in cases(py).items() if n.startswith("htn plan Towers")]
    return {
        "runs": runs,
        "figures": figures,
        "imports": imports(towers[0], top) if towers else [],
    }


def show(report: dict) -> None:
    runs = report["runs"]
    from rich.console import Console
    from rich.table import Table

    t = Table(
        title=f"whole-process CPU, median of {runs} cold runs; htn from {report['installed']}"
    )
    t.add_column("command")
    t.add_column("CPU s", justify="right")
    t.add_column("min s", justify="right")
    for name, f in report["figures"].items():
        t.add_row(name, f"{f['median_s']:.3f}", f"{f['min_s']:.3f}")
    Console().print(t)
    if report["imports"]:
        m = Table(title="htn plan Towers pfile_05: the costliest imports (own time)")
        m.add_column("module")
        m.add_column("ms", justify="right")
        for name, ms in report["imports"]:
            m.add_row(name, f"{ms:.1f}")
        Console().print(m)


if __name__ == "__main__":
    main()
