"""A plain ``htn plan DOMAIN PROBLEM`` runs without click (``htn.cli.fast``):
it prints, writes and ends exactly as the same command parsed by click does.
A command line the fast path does not take is given to click."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from htn.api.plan import DEFAULT_MAX_DEPTH
from htn.cli.fast import plain_plan

from conftest import ROOT, SHARED, run_htn

DOMESTIC = (str(ROOT / "domains" / "domestic.jshop"), str(ROOT / "problems" / "bring_object.jshop"))
TOWERS = SHARED / "corpus" / "ipc2020-to" / "Towers"
# the default --max-depth, given: the fast path leaves such a command line to click
BY_CLICK = ("--max-depth", str(DEFAULT_MAX_DEPTH))


def _untimed(text: str) -> str:
    """JSON Lines without the search's time, which differs from run to run."""
    text = re.sub(r'"search_ms":[0-9.e-]+', '"search_ms":_', text)
    return re.sub(r"search [0-9.]+ ms", "search _ ms", text)  # the text format's summary


def _both(*args):
    fast, slow = run_htn("plan", *args), run_htn("plan", *args, *BY_CLICK)
    assert plain_plan(["plan", *map(str, args)]) is not None
    assert plain_plan(["plan", *map(str, args), *BY_CLICK]) is None
    return fast, slow


@pytest.mark.parametrize(
    "options",
    [
        (),
        ("-f", "jshop"),
        ("--format", "json"),
        ("-f", "text", "-q"),
        ("--search", "dfs"),
        ("--search", "auto", "-f", "jshop"),
    ],
)
def test_the_fast_path_prints_what_click_s_path_prints(options):
    fast, slow = _both(*DOMESTIC, *options)
    assert fast.returncode == slow.returncode == 0
    assert _untimed(fast.stdout) == _untimed(slow.stdout)
    assert fast.stderr == slow.stderr
    assert "Plan cost: 8.0" in fast.stdout or '"cost":8.0' in fast.stdout or "cost 8" in fast.stdout


@pytest.mark.corpus
def test_an_hddl_instance_in_the_ipc_format_alike():
    if not TOWERS.is_dir():
        pytest.skip(f"{TOWERS} not found")
    fast, slow = _both(TOWERS / "domain.hddl", TOWERS / "pfile_05.hddl", "-f", "ipc")
    assert fast.returncode == slow.returncode == 0
    assert fast.stdout == slow.stdout and fast.stdout.startswith("==>")
    # --search auto (the IPC's usual command line) runs without click too
    fast, slow = _both(TOWERS / "domain.hddl", TOWERS / "pfile_05.hddl", "--search", "auto", "-q")
    assert fast.returncode == slow.returncode == 0
    assert _untimed(fast.stdout) == _untimed(slow.stdout) and fast.stderr == slow.stderr
    assert "(!move" in fast.stdout


def test_errors_and_no_plan_end_alike(tmp_path):
    bad = tmp_path / "bad.jshop"
    bad.write_text("(defdomain d ((:operator (!a) () () ()))")  # one ')' short
    for args in [(bad, DOMESTIC[1]), (tmp_path / "missing.jshop", DOMESTIC[1])]:
        fast, slow = _both(*args)
        assert fast.returncode == slow.returncode == 2
        assert fast.stderr == slow.stderr and fast.stderr.count("\n") <= 3
        assert "Traceback" not in fast.stderr
    stuck = tmp_path / "stuck.jshop"
    stuck.write_text("(defproblem p domestic ((at jenny home_base)) ((fly_to jenny moon)))\n")
    fast, slow = _both(DOMESTIC[0], stuck)
    assert fast.returncode == slow.returncode == 2 and fast.stderr == slow.stderr


@pytest.mark.parametrize(
    "args",
    [
        ["plan", "d", "p", "-o", "x.txt"],
        ["plan", "d", "p", "--format=ipc"],
        ["plan", "d", "p", "-f", "yaml"],
        ["plan", "d", "p", "-f"],
        ["plan", "d", "p", "--search", "gbfs"],
        ["plan", "d", "p", "--search", "wastar"],
        ["plan", "d", "p", "--search", "AUTO"],
        ["plan", "d", "p", "-q", "-q"],
        ["plan", "d", "p", "--help"],
        ["plan", "d"],
        ["plan", "d", "p", "extra"],
        ["plan", "d", "p", "--"],
        ["plan", ".", "p"],
        ["run", "d", "p"],
    ],
)
def test_what_the_fast_path_does_not_take_goes_to_click(args):
    assert plain_plan(args) is None


def test_a_plain_plan_as_a_process_imports_no_click_and_no_lark():
    code = (
        "import sys, runpy; sys.argv = ['htn', 'plan', *sys.argv[1:]];"
        "import htn.cli.main as m\n"
        "try:\n    m.main()\nexcept SystemExit:\n    pass\n"
        "print(sorted(x for x in ('click', 'lark', 'rich') if x in sys.modules), file=sys.stderr)"
    )
    r = subprocess.run(
        [sys.executable, "-c", code, *DOMESTIC, "-f", "jshop"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert "Plan cost: 8.0" in r.stdout
    # well-formed JSHOP2 input is read without the lark grammar; click and rich stay out
    assert r.stderr.strip().splitlines()[-1] == "[]"


def test_auto_on_a_small_hddl_instance_builds_no_heuristic_search():
    """Towers pfile_05: depth-first search plans it in its first turn, so
    the portfolio neither builds nor imports the heuristic searches."""
    if not (TOWERS / "pfile_05.hddl").is_file():
        pytest.skip(f"{TOWERS} not found")
    code = (
        "import sys; sys.argv = ['htn', 'plan', *sys.argv[1:]];"
        "import htn.cli.main as m\n"
        "try:\n    m.main()\nexcept SystemExit:\n    pass\n"
        "print(sorted(x for x in sys.modules if x.startswith('htn.jshop.search')), file=sys.stderr)"
    )
    r = subprocess.run(
        [sys.executable, "-c", code, TOWERS / "domain.hddl", TOWERS / "pfile_05.hddl"]
        + ["--search", "auto", "-f", "json"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert '"found_by":"dfs"' in r.stdout.replace(" ", ""), r.stdout[-2000:] + r.stderr[-2000:]
    loaded = r.stderr.strip().splitlines()[-1]
    assert "htn.jshop.search.portfolio" in loaded
    for module in ("best_first", "grounding", "heuristics", "reachability"):
        assert f"htn.jshop.search.{module}'" not in loaded, loaded
