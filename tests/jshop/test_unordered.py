"""``:unordered`` method bodies: the manual's interleavings by default, JSHOP2
1.0.3's in-order reading with ``--jshop2-compat`` (manual 3.8, 5.2.2).

The order in which plans come out is the manual's ``getFirst`` order: the
first tasks of an unordered list are those of each member in turn, and an
``:immediate`` task among them is the only option.
"""

from __future__ import annotations

import pytest

from conftest import run_htn

DOMAIN = """
(defdomain interleave (
  (:operator (!a1) () () ())
  (:operator (!a2) () () ())
  (:operator (!b) () () ())
  (:operator (!c) () () ())
  (:operator (!open) () () ((open)))
  (:operator (!check-closed) ((not (open))) () ())
  (:method (two) () (:unordered (!a1) (!b)))
  (:method (nested) () (:unordered ((!a1) (!a2)) (!b)))
  (:method (immediate) () (:unordered (!a1) (:immediate !b) (!c)))
  (:method (nested-immediate) () (:unordered ((!a1) (:immediate !a2)) (!b)))
  (:method (inner-unordered) () ((!c) (:unordered (!a1) (!b))))
  (:method (order-matters) () (:unordered (!open) (!check-closed)))
))
"""


def _plans(tmp_path, task: str, *flags) -> tuple[list[list[str]], object]:
    (tmp_path / "d.jshop").write_text(DOMAIN)
    (tmp_path / "p.jshop").write_text(f"(defproblem p interleave () (({task})))")
    result = run_htn(
        "plan", tmp_path / "d.jshop", tmp_path / "p.jshop", "--all", "-f", "jshop", *flags
    )
    assert "Traceback" not in result.stderr
    plans = [
        [line for line in block.splitlines() if line.startswith("(")]
        for block in result.stdout.split("--------------------")[:-1]
    ]
    return plans, result


@pytest.mark.parametrize(
    "task,expected",
    [
        ("two", [["(!a1)", "(!b)"], ["(!b)", "(!a1)"]]),
        (
            "nested",
            [["(!a1)", "(!a2)", "(!b)"], ["(!a1)", "(!b)", "(!a2)"], ["(!b)", "(!a1)", "(!a2)"]],
        ),
        ("immediate", [["(!b)", "(!a1)", "(!c)"], ["(!b)", "(!c)", "(!a1)"]]),
        ("nested-immediate", [["(!a1)", "(!a2)", "(!b)"], ["(!b)", "(!a1)", "(!a2)"]]),
        ("inner-unordered", [["(!c)", "(!a1)", "(!b)"], ["(!c)", "(!b)", "(!a1)"]]),
    ],
)
def test_interleavings_in_getfirst_order(tmp_path, task, expected):
    plans, result = _plans(tmp_path, task)
    assert result.returncode == 0, result.stderr
    assert plans == expected


@pytest.mark.parametrize(
    "task,expected",
    [
        ("two", [["(!a1)", "(!b)"]]),
        ("nested", [["(!a1)", "(!a2)", "(!b)"]]),
        ("immediate", [["(!a1)", "(!b)", "(!c)"]]),
        # a nested :unordered list keeps its meaning in JSHOP2 1.0.3 too
        ("inner-unordered", [["(!c)", "(!a1)", "(!b)"], ["(!c)", "(!b)", "(!a1)"]]),
    ],
)
def test_jshop2_compat_runs_top_level_bodies_in_order(tmp_path, task, expected):
    plans, result = _plans(tmp_path, task, "--jshop2-compat")
    assert result.returncode == 0, result.stderr
    assert plans == expected


def test_compat_warns_once_with_the_first_body_location(tmp_path):
    _, result = _plans(tmp_path, "two", "--jshop2-compat")
    lines = [line for line in result.stderr.splitlines() if "warning" in line]
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"{tmp_path / 'd.jshop'}:9:")
    assert "runs in order" in lines[0] and "and 4 more" in lines[0]
    _, result = _plans(tmp_path, "two")
    assert "warning" not in result.stderr


def test_order_that_only_an_unordered_body_allows(tmp_path):
    """Checking before opening is the only plan; in order it fails."""
    plans, result = _plans(tmp_path, "order-matters")
    assert result.returncode == 0, result.stderr
    assert plans == [["(!check-closed)", "(!open)"]]
    plans, result = _plans(tmp_path, "order-matters", "--jshop2-compat")
    assert result.returncode == 1 and plans == []
