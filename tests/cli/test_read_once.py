"""Every input file is read once (issue 35): ``htn run`` opens the plan
file, the domain, the problem and the functions file exactly once each
(an ``open`` audit hook counts them), parses those bytes, and its log
header's SHA-256 values are those of the bytes it read; ``htn plan -o``
records the functions file's SHA-256 from the bytes it loaded."""

from __future__ import annotations

import hashlib
import json
import subprocess
import sys
from collections import Counter

from conftest import ROOT, run_htn

AUDIT = """
import os, sys
fd = os.open(sys.argv[1], os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
watched = {os.path.realpath(p) for p in sys.argv[2].split(os.pathsep)}
def hook(event, args):
    if event == "open" and args and isinstance(args[0], (str, bytes)):
        path = os.path.realpath(os.fsdecode(args[0]))
        if path in watched:
            os.write(fd, (path + "\\n").encode())
sys.addaudithook(hook)
sys.argv = ["htn", *sys.argv[3:]]
from htn.cli.start import main
main()
"""
FUNCTIONS = "def weight(x):\n    return 1\n"


def test_htn_run_reads_each_file_once_and_logs_the_hashes_of_what_it_read(tmp_path):
    domain, problem = tmp_path / "domestic.jshop", tmp_path / "bring_object.jshop"
    domain.write_text((ROOT / "domains" / "domestic.jshop").read_text())
    problem.write_text((ROOT / "problems" / "bring_object.jshop").read_text())
    functions, plan, log = tmp_path / "fns.py", tmp_path / "plan.txt", tmp_path / "run.jsonl"
    functions.write_text(FUNCTIONS)
    r = run_htn("plan", domain, problem, "--functions", functions, "-o", plan)
    assert r.returncode == 0, r.stderr
    digest = {
        p: hashlib.sha256(p.read_bytes()).hexdigest() for p in (plan, domain, problem, functions)
    }
    assert f"; functions sha256: {digest[functions]}" in plan.read_text()

    opened = tmp_path / "opened.txt"
    watched = [plan, domain, problem, functions]
    r = subprocess.run(
        [
            sys.executable,
            "-c",
            AUDIT,
            opened,
            ":".join(str(p.resolve()) for p in watched),
            "run",
            plan,
            "--robot",
            "symbolic",
            "-q",
            "--functions",
            functions,
            "--log",
            log,
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert r.returncode == 0, r.stderr
    counts = Counter(opened.read_text().split())
    assert counts == Counter({str(p.resolve()): 1 for p in watched}), counts

    header = json.loads(log.read_text().splitlines()[0])
    assert header["plan_sha256"] == digest[plan]
    assert header["domain_sha256"] == digest[domain]
    assert header["problem_sha256"] == digest[problem]
    assert header["functions_sha256"] == digest[functions]


def test_a_functions_file_that_is_not_the_plans_is_refused_before_it_runs(tmp_path):
    domain, problem = ROOT / "domains" / "domestic.jshop", ROOT / "problems" / "bring_object.jshop"
    functions, plan = tmp_path / "fns.py", tmp_path / "plan.txt"
    functions.write_text(FUNCTIONS)
    assert run_htn("plan", domain, problem, "--functions", functions, "-o", plan).returncode == 0
    marker = tmp_path / "ran"
    functions.write_text(f"open({str(marker)!r}, 'w').close()\n" + FUNCTIONS)
    r = run_htn("run", plan, "--robot", "symbolic", "-q", "--functions", functions)
    assert (
        r.returncode == 2 and "is not the functions file these plans were made with" in r.stderr
    ), r.stderr
    assert not marker.exists()
