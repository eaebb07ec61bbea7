"""The coffee-robot session of issue 19, replayed: every command that reads a
domain and a problem (plan, validate, stats, transform, run, evaluate) runs
the one static check (htn.jshop.readers.checks.check_inputs), so an add-list
variable nothing binds is refused by all six the same way: exit 2 and the
same located line. And ``htn evaluate`` refuses a study it cannot measure,
finds a domain beside its problem, and names every place it looked.
"""

from __future__ import annotations

from coffee import COFFEE, MORNING
from inprocess import run_cli

UNBOUND = COFFEE.replace("((has ?person ?cup))", "((has ?someone ?cup))", 1)
WHERE = "coffee.jshop:16:6: operator !hand adds (has ...) with ?someone unbound"


def _write(folder, domain=COFFEE):
    (folder / "coffee.jshop").write_text(domain)
    (folder / "morning.jshop").write_text(MORNING)


def test_every_command_refuses_the_unbound_add_the_same_located_way(tmp_path):
    _write(tmp_path)
    made = run_cli("plan", "coffee.jshop", "morning.jshop", "-o", "plan.txt", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    (tmp_path / "coffee.jshop").write_text(UNBOUND)
    commands = {
        "plan": ["plan", "coffee.jshop", "morning.jshop"],
        "validate": ["validate", "coffee.jshop", "morning.jshop", "plan.txt"],
        "stats": ["stats", "coffee.jshop", "morning.jshop"],
        "transform": ["transform", "coffee.jshop", "morning.jshop"],
        "run": [
            "run",
            "plan.txt",
            "--robot",
            "symbolic",
            "--domain",
            "coffee.jshop",
            "--problem",
            "morning.jshop",
        ],
        "evaluate": ["evaluate", "morning.jshop", "--runs", "2"],  # its domain found beside
    }
    first_lines = {}
    for name, args in commands.items():
        r = run_cli(*args, cwd=tmp_path)
        assert r.returncode == 2, (name, r.stdout, r.stderr)
        assert r.stdout == "", (name, r.stdout)
        assert "Traceback" not in r.stderr
        first_lines[name] = r.stderr.splitlines()[0]
    assert first_lines["plan"].startswith(WHERE), first_lines["plan"]
    assert set(first_lines.values()) == {first_lines["plan"]}, first_lines
    assert not (tmp_path / "run.jsonl").exists()


def test_evaluate_refuses_a_study_it_cannot_measure(tmp_path):
    # the coffee robot plans, but no registered rule rewrites its plan and the
    # projection robot has no action for its steps: every number would be 0
    _write(tmp_path)
    r = run_cli("evaluate", "morning.jshop", "--runs", "5", cwd=tmp_path)
    assert r.returncode == 2, (r.stdout, r.stderr)
    assert r.stdout == ""
    [line] = r.stderr.splitlines()
    assert line.startswith(
        "morning.jshop: htn evaluate compares a plan with its transformed "
        "plan, but no registered transformation (tray, container, both-hands)"
        " applies to its plan"
    ), line
    assert "the projection robot has no action for !goto, !brew, !hand" in line
    assert "'htn.transformations'" in line and "'htn.actions'" in line


def test_evaluate_names_every_place_it_looked_for_the_domain(tmp_path):
    (tmp_path / "problems").mkdir()
    (tmp_path / "problems" / "morning.jshop").write_text(MORNING)
    r = run_cli("evaluate", "problems/morning.jshop", cwd=tmp_path)
    assert r.returncode == 2, (r.stdout, r.stderr)
    [line] = r.stderr.splitlines()
    assert line.startswith(
        "problems/morning.jshop: cannot find the domain file coffee.jshop: "
        "looked in problems/, domains/ and "
    ), line
    assert line.endswith("/domains/; give it with --domain"), line
    # beside the problem is the first place looked
    (tmp_path / "problems" / "coffee.jshop").write_text(UNBOUND)
    r = run_cli("evaluate", "problems/morning.jshop", cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.startswith("problems/" + WHERE), r.stderr
