"""The searches of ``htn plan --search`` on the IPC samples: each plan is
checked as the competition's verifier does (decompositions against the
domain), with ``htn validate``, and with pandaPIparser when the binary is
there. ``ipc2020-to`` (total order) is planned with every search in
``test_hddl.py``; here ``ipc-po`` (partial order) with ``auto``, one
instance of each domain that it solves within seconds (the whole sample,
solved in up to 30 s of CPU each: ``benchmarks/bench_ipc.py --sample ipc-po
--search auto``)."""

from __future__ import annotations

import json
import subprocess

import pytest
from test_hddl import check_ipc_decomposition

from conftest import SHARED, run_htn

PANDA = SHARED / "tools" / "pandaPIparser" / "pandaPIparser"
TOTAL = SHARED / "corpus" / "ipc2020-to"
PARTIAL = SHARED / "corpus" / "ipc-po"
pytestmark = pytest.mark.corpus
# one instance of each ipc-po domain that auto solves in a few seconds
# (Monroe-Partially-Observable takes 25 s or more)
QUICK_PO = {
    "Barman-BDI-pfile04",
    "Colouring-pfile05",
    "Monroe-Fully-Observable-pfile13-p-0028-set-up-shelter-1-tlt",
    "PCP-p-pcp12",
    "Rover-pfile01",
    "Satellite-2obs-1sat-1mod",
    "Transport-pfile02",
    "UM-Translog-06-A-AutoTruck",
    "Ultralight-Cockpit-pfile04",
    "Woodworking-01--p01-complete",
}


def _domain_of(problem):
    own = problem.with_name(problem.stem + "-domain.hddl")
    if own.is_file():
        return own
    return next(problem.parent.glob("*domain.hddl"))


def _instances(folder, only=None):
    if not (folder / "README.md").is_file():
        return [pytest.param(None, None, marks=pytest.mark.skip(reason=f"{folder} not found"))]
    out = []
    for sub in sorted(p for p in folder.iterdir() if p.is_dir()):
        for problem in sorted(sub.glob("*.hddl")):
            if problem.name.endswith("domain.hddl"):
                continue
            name = f"{sub.name}-{problem.stem}"
            if only is None or name in only:
                out.append(pytest.param(_domain_of(problem), problem, id=name))
    return out


def _check(tmp_path, domain, problem, search):
    plan_file = tmp_path / "plan.txt"
    result = run_htn(
        "plan",
        domain,
        problem,
        "-f",
        "ipc",
        "-o",
        plan_file,
        "-q",
        "--search",
        search,
        "--timeout",
        "600",
    )
    assert result.returncode == 0, result.stderr
    steps = [
        tuple(line.strip("()").replace("!", "", 1).split())
        for line in plan_file.read_text().splitlines()
        if line.startswith("(")
    ]
    check_ipc_decomposition(result.stdout, domain, problem, steps, ordered=False)
    valid = run_htn("validate", domain, problem, plan_file)
    assert valid.returncode == 0, valid.stdout + valid.stderr
    if PANDA.is_file():
        ipc = tmp_path / "plan.ipc"
        ipc.write_text(result.stdout)
        verdict = subprocess.run(
            [str(PANDA), "-C", "--verify", str(domain), str(problem), str(ipc)],
            capture_output=True,
            text=True,
        )
        assert "Plan verification result: true" in verdict.stdout, verdict.stdout[-2000:]


@pytest.mark.slow
@pytest.mark.parametrize("domain,problem", _instances(PARTIAL, QUICK_PO))
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


UL = PARTIAL / "Ultralight-Cockpit"


@pytest.mark.parametrize(
    "name,fact,anchor",
    [
        ("pfile02", "(p_reachable aerodrome1)", "(p_landingSpotClear aerodrome2)"),
        ("pfile03", "(p_landingSpotClear aerodrome2)", "(p_reachable aerodrome2)"),
    ],
)
def test_ultralight_no_plan_is_the_answer(tmp_path, name, fact, anchor):
    """The two "no plan" answers on ipc-po are right, and one fact away from
    a plan: the only method of ``precautionary_land`` flies over a landing
    spot (``m_perform_fly_over`` needs ``p_reachable``; its alternative
    needs ``p_controlParameterReached``, which nothing adds) and then lands
    there (``m_land`` needs ``p_landingSpotClear``, which nothing adds).
    pfile02 has no reachable spot; in pfile03 the reachable one is not
    clear. With the missing fact in the initial state, the search finds a
    plan that both verifiers accept."""
    domain, problem = UL / "UL_domain.hddl", UL / f"{name}.hddl"
    if not problem.is_file():
        pytest.skip(f"{problem} not found")
    result = run_htn("plan", domain, problem, "--search", "gbfs", "-f", "json", "-q")
    stats = json.loads(result.stdout.splitlines()[-1])
    assert result.returncode == 1 and stats["plans_found"] == 0, result.stdout + result.stderr
    assert not (stats["timed_out"] or stats["memory_limit_reached"])  # the space was exhausted
    text = problem.read_text()
    assert anchor in text and fact not in text.replace(";(not " + fact, "")
    changed = tmp_path / f"{name}.hddl"
    changed.write_text(text.replace(anchor, f"{anchor} {fact}", 1))
    _check(tmp_path, domain, changed, "gbfs")
