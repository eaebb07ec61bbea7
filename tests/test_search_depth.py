"""The search depth bound: a method that decomposes into itself ends with a
message naming the recursing task, exit code 1, in bounded memory."""
from __future__ import annotations

import json

import resource
import subprocess
import sys

from conftest import ROOT, run_htn

DOMAIN = """(defdomain loop (
  (:operator (!a) () () ())
  (:method (loop) () ((loop) (!a)))
))
"""
PROBLEM = "(defproblem p loop () ((loop)))\n"


def _files(tmp_path):
    (tmp_path / "loop.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text(PROBLEM)
    return tmp_path / "loop.jshop", tmp_path / "p.jshop"


def _limit_memory():
    one_gb = 1 << 30
    resource.setrlimit(resource.RLIMIT_AS, (one_gb, one_gb))


def test_runaway_recursion_stops_at_the_default_depth_within_1_gb(tmp_path):
    domain, problem = _files(tmp_path)
    # the whole process may use at most 1 GB of address space
    result = subprocess.run([sys.executable, "-m", "htn", "plan", str(domain), str(problem)],
                            cwd=ROOT, capture_output=True, text=True, timeout=120,
                            preexec_fn=_limit_memory)
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr and "MemoryError" not in result.stderr
    assert f"{domain}:3:24: task (loop) recurses past the search depth limit" in result.stderr
    assert "--max-depth" in result.stderr
    assert result.stdout == ""


def test_max_depth_option(tmp_path):
    domain, problem = _files(tmp_path)
    result = run_htn("plan", domain, problem, "--max-depth", "50", "-f", "json")
    assert result.returncode == 1
    assert "(50 nested reductions and steps)" in result.stderr
    assert json.loads(result.stdout.splitlines()[-1])["depth_limit_reached"] is True
    # a plan that fits is found
    (tmp_path / "q.jshop").write_text("(defproblem q loop () ((!a) (!a)))\n")
    result = run_htn("plan", domain, tmp_path / "q.jshop", "--max-depth", "3", "-f", "jshop")
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("(!a)") == 2
    result = run_htn("plan", domain, problem, "--max-depth", "0")
    assert result.returncode == 2 and "--max-depth" in result.stderr
