"""UP's own engine test runner (``up_test_cases/report.py``, as UP's
documentation runs it) on htn, registered through an ``up.ini`` file as UP
documents for engines outside its list: every hierarchical case whose kind
htn declares passes (oneshot and validation), the others are skipped."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest

pytest.importorskip("unified_planning")

from test_up_cases import REFUSED, SUPPORTED, report_script  # noqa: E402


@pytest.fixture(scope="module")
def report(tmp_path_factory) -> tuple[int, str]:
    home = tmp_path_factory.mktemp("home")
    (home / "up.ini").write_text(
        "[engine htn]\nmodule_name: htn.up.engine\nclass_name: HtnEngine\n"
    )
    env = {**os.environ, "HOME": str(home)}
    r = subprocess.run(
        [
            sys.executable,
            report_script(),
            "htn",
            "-p",
            "builtin.hierarchical",
            "unified_planning.test",
            "-m",
            "oneshot",
            "validation",
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=home,
        timeout=900,
    )
    return r.returncode, re.sub(r"\x1b\[[0-9;]*m", "", r.stdout + r.stderr)


def _results(out: str, section: str) -> dict:
    """Test case -> htn's result line in one section of the report."""
    body = out.split(section, 1)[1].split("\n\n\n", 1)[0]
    found, case = {}, None
    for line in body.splitlines():
        if line and not line.startswith("|"):
            case = line.strip()
        elif line.startswith("|   htn"):
            found[case] = line
    return found


def test_every_case_of_the_declared_kind_passes_and_the_rest_is_skipped(report):
    code, out = report
    assert code == 0, out[-3000:]
    assert "CRASH" not in out and "Err(" not in out and "errors:" not in out
    oneshot = _results(out, "ONESHOT PLANNING:")
    for name in SUPPORTED:
        (line,) = [v for k, v in oneshot.items() if k.endswith(":" + name)]
        assert "SOLVED_SATISFICING" in line and "OK(Valid)" in line, line
    assert not any(k.endswith(":" + name) for k in oneshot for name in REFUSED)
    skipped = out.split("Oneshot problems skipped:", 1)[1].split("\n\n\n", 1)[0]
    for name in REFUSED:
        assert name in skipped
    validation = _results(out, "VALIDATION")
    (line,) = [v for k, v in validation.items() if "htn-go valid[0]" in k]
    assert "VALID" in line and "OK(Valid)" in line
