"""The hostile-user fuzz run in the suite (issue 34): HDDL models with the
slips a modeller makes, mutated HDDL and JSHOP2 files, and option values of
every kind, through ``plan``, ``stats``, ``transform``, ``validate`` and
``run`` (the inputs: :mod:`fuzz_inputs`). Every answer is exit code 0, 1 or
2 without a traceback, an exit 2 about a file is located in it, and no
input file changes.

CI draws ``HTN_FUZZ_INPUTS`` inputs (default 200, derandomized: about 25 s
on one core). ``benchmarks/fuzz_long.py`` runs the same generator with fresh
seeds for as many inputs as asked, and sums the tallies this test writes to
``HTN_FUZZ_TALLY`` (a file, one JSON object per run of the test).
"""

from __future__ import annotations

import json
import os
import time
from collections import Counter
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings

from conftest import run_htn
from fuzz_inputs import HDDL, JSHOP2, inputs, verdict

EXAMPLES = int(os.environ.get("HTN_FUZZ_INPUTS", "200"))
RANDOM = bool(os.environ.get("HTN_FUZZ_RANDOM"))
PHASES = [Phase.generate] if RANDOM else list(Phase)
TALLY: Counter = Counter()


@pytest.fixture(scope="module", autouse=True)
def _report():
    yield
    if not TALLY:
        return
    print(
        f"\nfuzz-inputs: {sum(v for k, v in TALLY.items() if k.startswith('exit '))} "
        "inputs; " + ", ".join(f"{k} {v}" for k, v in sorted(TALLY.items()))
    )
    if os.environ.get("HTN_FUZZ_TALLY"):
        with open(os.environ["HTN_FUZZ_TALLY"], "a", encoding="utf-8") as fh:
            fh.write(json.dumps(dict(TALLY)) + "\n")


@pytest.fixture(scope="module")
def plan_files(tmp_path_factory):
    """A plan file of each unmutated example, made when first asked for
    (None where none is found in 3 s); kept in ``HTN_FUZZ_PLANS`` (a
    folder) across runs when that is set."""
    keep = os.environ.get("HTN_FUZZ_PLANS")
    folder = Path(keep) if keep else tmp_path_factory.mktemp("plans")
    cases = {name: (d, p) for name, d, p in HDDL + JSHOP2}
    made: dict = {}

    def plan_of(name: str):
        if name not in made:
            d, p = cases[name]
            ext = "hddl" if d.lstrip().startswith("(define") else "jshop"
            base = folder / name.replace("/", "_")
            out, none = base / "plan.txt", base / "no-plan"
            if not (out.is_file() or none.is_file()):
                base.mkdir(parents=True, exist_ok=True)
                (base / f"d.{ext}").write_text(d)
                (base / f"p.{ext}").write_text(p)
                r = run_htn(
                    "plan", base / f"d.{ext}", base / f"p.{ext}", "-o", out, "--timeout", "3"
                )
                if r.returncode != 0:
                    none.touch()
            made[name] = out if out.is_file() else None
        return made[name]

    return plan_of


@pytest.mark.slow
@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=not RANDOM,
    database=None,
    suppress_health_check=list(HealthCheck),
    phases=PHASES,
)
@given(inp=inputs())
def test_every_input_gets_a_clean_answer(tmp_path_factory, plan_files, inp):
    plan_file = plan_files(inp.case) if inp.command in ("run", "validate") else None
    if inp.command in ("run", "validate") and plan_file is None:
        inp.command = "plan"  # the example has no plan in time: plan it instead
    folder = tmp_path_factory.mktemp("input")
    for name, data in inp.files.items():
        (folder / name).write_bytes(data)
    argv = inp.argv(folder, plan_file)
    files = [folder / n for n in inp.files] + ([plan_file] if plan_file else [])
    before = {f: f.read_bytes() for f in files}
    began = time.monotonic()
    r = run_htn(*argv, timeout=300)
    took = time.monotonic() - began
    TALLY[f"exit {r.returncode}"] += 1
    TALLY[f"kind {inp.kind}"] += 1
    TALLY[f"kind {inp.kind} exit {r.returncode}"] += 1
    TALLY[f"command {inp.command}"] += 1
    if took > 1.5 and os.environ.get("HTN_FUZZ_SLOW"):
        import shutil

        keep = shutil.copytree(folder, os.path.join(os.environ["HTN_FUZZ_SLOW"], folder.name))
        with open(os.path.join(keep, "argv.txt"), "w") as fh:
            fh.write(" ".join(map(str, argv)) + f"\n{took} {r.returncode}\n{r.stderr}")
    if os.environ.get("HTN_FUZZ_SHOW"):
        print(
            f"{took:6.2f}s exit {r.returncode} {inp.kind:14} {inp.command:9} {inp.detail[:60]} "
            f"{' '.join(map(str, inp.options))[:40]} | {r.stderr.strip()[-100:]!r}"
        )
    problem = verdict(r.returncode, r.stderr, files)
    assert problem is None, (problem, inp.kind, inp.detail, argv, r.stderr[-1500:])
    for f, data in before.items():
        assert f.read_bytes() == data, f"{f} changed: {argv}"
    # every command here is bounded by --timeout 0.5 (or the drawn one, at
    # most a few seconds for stats); the watchdog's grace is 3 s
    assert took < 60, (took, argv)
