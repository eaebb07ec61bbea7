"""The search's bounds: a method that decomposes into itself before any step
ends at the reduction-depth bound, a search that never ends but applies
operators at the memory budget, each with a message naming the task, exit
code 1, in bounded memory; a long plan is bounded by neither."""

from __future__ import annotations

import json
import resource
import subprocess
import sys

import pytest

from conftest import ROOT, run_htn

DOMAIN = """(defdomain loop (
  (:operator (!a) () () ())
  (:method (loop) () ((loop) (!a)))
))
"""
PROBLEM = "(defproblem p loop () ((loop)))\n"


# a tail recursion: every reduction is followed by a step, so the plan just grows
TAIL_DOMAIN = """(defdomain tail (
  (:operator (!a ?n) () () ())
  (:method (count ?n) ((call > ?n 0)) ((!a ?n) (count (call - ?n 1))))
  (:method (count 0) () ())
  (:method (forever) () ((!a 0) (forever)))
))
"""


def _files(tmp_path):
    (tmp_path / "loop.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text(PROBLEM)
    return tmp_path / "loop.jshop", tmp_path / "p.jshop"


def _limit_memory():
    one_gb = 1 << 30
    resource.setrlimit(resource.RLIMIT_AS, (one_gb, one_gb))


@pytest.mark.slow
def test_runaway_recursion_stops_at_the_default_depth_within_1_gb(tmp_path):
    domain, problem = _files(tmp_path)
    # the whole process may use at most 1 GB of address space
    result = subprocess.run(
        [sys.executable, "-m", "htn", "plan", str(domain), str(problem)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_limit_memory,
    )
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr and "MemoryError" not in result.stderr
    assert f"{domain}:3:24: task (loop) recurses past the search depth limit" in result.stderr
    assert "--max-depth" in result.stderr
    assert result.stdout == ""


def test_max_depth_option(tmp_path):
    domain, problem = _files(tmp_path)
    result = run_htn("plan", domain, problem, "--max-depth", "50", "-f", "json")
    assert result.returncode == 1
    assert "(50 nested reductions without a step)" in result.stderr
    assert json.loads(result.stdout.splitlines()[-1])["depth_limit_reached"] is True
    # a plan that fits is found
    (tmp_path / "q.jshop").write_text("(defproblem q loop () ((!a) (!a)))\n")
    result = run_htn("plan", domain, tmp_path / "q.jshop", "--max-depth", "3", "-f", "jshop")
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("(!a)") == 2
    result = run_htn("plan", domain, problem, "--max-depth", "0")
    assert result.returncode == 2 and "--max-depth" in result.stderr


def test_a_plan_longer_than_the_depth_bound_is_found(tmp_path):
    (tmp_path / "tail.jshop").write_text(TAIL_DOMAIN)
    (tmp_path / "p.jshop").write_text("(defproblem p tail () ((count 300)))\n")
    result = run_htn(
        "plan", tmp_path / "tail.jshop", tmp_path / "p.jshop", "--max-depth", "5", "-f", "jshop"
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("(!a ") == 300


@pytest.mark.slow
def test_endless_plan_stops_at_the_memory_budget_within_1_gb(tmp_path):
    (tmp_path / "tail.jshop").write_text(TAIL_DOMAIN)
    (tmp_path / "p.jshop").write_text("(defproblem p tail () ((forever)))\n")
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "htn",
            "plan",
            str(tmp_path / "tail.jshop"),
            str(tmp_path / "p.jshop"),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=_limit_memory,
    )
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr and "MemoryError" not in result.stderr
    assert (
        "tail.jshop:5:34: the search used its memory budget (819 MB) at task (forever)"
        in result.stderr
    )
    assert "--max-memory" in result.stderr


def test_max_memory_option(tmp_path):
    (tmp_path / "tail.jshop").write_text(TAIL_DOMAIN)
    (tmp_path / "p.jshop").write_text("(defproblem p tail () ((forever)))\n")
    result = run_htn(
        "plan", tmp_path / "tail.jshop", tmp_path / "p.jshop", "--max-memory", "120", "-f", "json"
    )
    assert result.returncode == 1
    assert "memory budget (120 MB)" in result.stderr
    stats = json.loads(result.stdout.splitlines()[-1])
    assert stats["memory_limit_reached"] is True and stats["plans_found"] == 0
    assert stats["depth_limit_reached"] is False  # the bound that stopped it, only
