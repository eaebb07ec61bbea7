"""The in-process runner of the tests (:mod:`inprocess`) gives what
``python -m htn`` gives, and puts the process back as it found it."""

from __future__ import annotations

import os
import signal
import warnings

import pytest

from conftest import ROOT, run_htn, run_htn_process
from inprocess import LeakedState

DOMESTIC = ROOT / "domains" / "domestic.jshop"
BRING = ROOT / "problems" / "bring_object.jshop"


def _same(*args, **kw):
    here, there = run_htn(*args, **kw), run_htn_process(*args, **kw)
    assert (here.returncode, here.stdout, here.stderr) == (
        there.returncode,
        there.stdout,
        there.stderr,
    ), args
    return here


def test_the_same_answers_as_a_process(tmp_path):
    bad = tmp_path / "p.jshop"
    bad.write_text("(defproblem p domestic () ((fly)))")
    plan = tmp_path / "plan.txt"
    assert _same("plan", DOMESTIC, BRING, "-f", "jshop", "-n", "2").returncode == 0
    assert _same("plan", DOMESTIC, bad).returncode == 2  # file:line:col, exit 2
    assert _same("plan", DOMESTIC, BRING, "--bogus").returncode == 2  # click's usage error
    assert _same("--help").stdout.startswith("Usage: htn")
    _same("plan", DOMESTIC, BRING, "-o", plan, "-q")
    assert _same("run", plan, "--robot", "symbolic", "--faults", "effect=1").returncode == 1
    assert _same("validate", DOMESTIC, BRING, plan).returncode == 0


def test_the_working_folder_environment_and_streams_are_put_back(tmp_path):
    before = (
        os.getcwd(),
        dict(os.environ),
        signal.getsignal(signal.SIGINT),
        signal.getsignal(signal.SIGTERM),
        warnings.filters[:],
    )
    r = run_htn(
        "plan",
        "domains/domestic.jshop",
        "problems/bring_object.jshop",
        env={**os.environ, "HTN_TEST_ONLY": "1"},
    )
    assert r.returncode == 0  # relative paths: run from the checkout's root
    assert (
        os.getcwd(),
        dict(os.environ),
        signal.getsignal(signal.SIGINT),
        signal.getsignal(signal.SIGTERM),
        warnings.filters[:],
    ) == before
    assert "HTN_TEST_ONLY" not in os.environ


def test_a_command_that_leaves_a_handler_behind_fails_the_test(tmp_path):
    # a user function changes SIGPIPE's handler and nobody puts it back
    d, p, fns = tmp_path / "d.jshop", tmp_path / "p.jshop", tmp_path / "fns.py"
    d.write_text("(defdomain d ((:operator (!a) ((call grab)) () ())))")
    p.write_text("(defproblem p d () ((!a)))")
    fns.write_text(
        "import signal\ndef grab():\n"
        "    signal.signal(signal.SIGPIPE, signal.SIG_DFL)\n    return 1\n"
    )
    handler = signal.getsignal(signal.SIGPIPE)
    with pytest.raises(LeakedState, match="SIGPIPE handler"):
        run_htn("plan", d, p, "--functions", fns)
    assert signal.getsignal(signal.SIGPIPE) == handler  # and it is put back


def test_a_signal_a_user_function_blocks_is_unblocked_by_htn(tmp_path):
    # htn itself restores the mask its caller had (htn.process)
    d, p, fns = tmp_path / "d.jshop", tmp_path / "p.jshop", tmp_path / "fns.py"
    d.write_text("(defdomain d ((:operator (!a) ((call block)) () ())))")
    p.write_text("(defproblem p d () ((!a)))")
    fns.write_text(
        "import signal\ndef block():\n"
        "    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})\n"
        "    return 1\n"
    )
    assert run_htn("plan", d, p, "--functions", fns).returncode == 0
    assert signal.SIGTERM not in signal.pthread_sigmask(signal.SIG_BLOCK, ())


def test_what_only_a_new_process_reads_is_refused():
    with pytest.raises(ValueError, match="PYTHONWARNINGS .* run_htn_process"):
        run_htn("--version", env={**os.environ, "PYTHONWARNINGS": "always"})
