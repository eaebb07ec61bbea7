"""Every search of ``htn plan --search`` on the IPC samples: each plan is
checked as the competition's verifier does (decompositions against the
domain), with ``htn validate``, and with pandaPIparser when the binary is
there. ``ipc2020-to`` (total order) for every search; ``ipc-po`` (partial
order) for ``auto``, which must solve every instance known to have a plan."""
from __future__ import annotations

import json
import subprocess

import pytest
from conftest import SHARED, run_htn

from test_hddl import check_ipc_decomposition

PANDA = SHARED / "tools" / "pandaPIparser" / "pandaPIparser"
TOTAL = SHARED / "corpus" / "ipc2020-to"
PARTIAL = SHARED / "corpus" / "ipc-po"
# instances of ipc-po for which no search here finds a plan, and none is known
NO_PLAN_KNOWN = {"Ultralight-Cockpit-pfile02", "Ultralight-Cockpit-pfile03"}


def _domain_of(problem):
    own = problem.with_name(problem.stem + "-domain.hddl")
    if own.is_file():
        return own
    return next(problem.parent.glob("*domain.hddl"))


def _instances(folder, skip=()):
    if not (folder / "README.md").is_file():
        return [pytest.param(None, None, marks=pytest.mark.skip(reason=f"{folder} not found"))]
    out = []
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        for problem in sorted(sub.glob("*.hddl")):
            if problem.name.endswith("domain.hddl"):
                continue
            name = f"{sub.name}-{problem.stem}"
            if name not in skip:
                out.append(pytest.param(_domain_of(problem), problem, id=name))
    return out


def _check(tmp_path, domain, problem, search):
    plan_file = tmp_path / "plan.txt"
    result = run_htn("plan", domain, problem, "-f", "ipc", "-o", plan_file, "-q",
                     "--search", search, "--timeout", "600")
    assert result.returncode == 0, result.stderr
    steps = [tuple(line.strip("()").replace("!", "", 1).split())
             for line in plan_file.read_text().splitlines() if line.startswith("(")]
    check_ipc_decomposition(result.stdout, domain, problem, steps)
    valid = run_htn("validate", domain, problem, plan_file)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    if PANDA.is_file():
        ipc = tmp_path / "plan.ipc"
        ipc.write_text(result.stdout)
        verdict = subprocess.run([str(PANDA), "-C", "--verify", str(domain), str(problem),
                                  str(ipc)], capture_output=True, text=True)
        assert "Plan verification result: true" in verdict.stdout, verdict.stdout[-2000:]


@pytest.mark.slow
@pytest.mark.parametrize("search", ["gbfs", "wastar", "auto"])
@pytest.mark.parametrize("domain,problem", _instances(TOTAL))
def test_total_order_sample(tmp_path, domain, problem, search):
    _check(tmp_path, domain, problem, search)


@pytest.mark.slow
@pytest.mark.parametrize("domain,problem", _instances(PARTIAL, skip=NO_PLAN_KNOWN))
def test_partial_order_sample_auto(tmp_path, domain, problem):
    _check(tmp_path, domain, problem, "auto")


@pytest.mark.parametrize("search", ["gbfs", "auto"])
def test_one_sample_instance_per_search(tmp_path, search):
    """The quick check of the slow ones: one small instance of each sample."""
    for folder, name in ((TOTAL, "Towers-pfile_05"), (PARTIAL, "Transport-pfile02")):
        found = [p for p in _instances(folder) if p.id == name]
        if not found or found[0].values[0] is None:
            pytest.skip(f"{folder} not found")
        domain, problem = found[0].values
        _check(tmp_path, domain, problem, search)
    if search == "auto":
        d, p = found[0].values
        result = run_htn("plan", d, p, "-f", "json", "--search", "auto", "-q")
        assert json.loads(result.stdout.splitlines()[-1])["found_by"] in ("dfs", "gbfs")
