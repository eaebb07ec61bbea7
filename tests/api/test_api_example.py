"""The Python API page's example (``examples/plan_and_run.py``) runs as a
new user runs it: on the core install (a wheel of this checkout in a fresh
virtualenv, no extras), from a folder outside the checkout."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

from conftest import ROOT

EXAMPLE = ROOT / "examples" / "plan_and_run.py"


def _sh(*args, cwd, env=None):
    return subprocess.run(
        [str(a) for a in args], cwd=cwd, capture_output=True, text=True, timeout=900, env=env
    )


@pytest.mark.slow
def test_the_example_runs_outside_the_checkout_on_the_core_install(tmp_path, checkout_wheel):
    wheel = checkout_wheel
    venv = tmp_path / "venv"
    assert _sh(sys.executable, "-m", "venv", venv, cwd=tmp_path).returncode == 0
    python = venv / "bin" / "python"
    r = _sh(python, "-m", "pip", "install", "-q", wheel, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    work = tmp_path / "work"
    work.mkdir()
    assert ROOT not in work.parents
    shutil.copy(EXAMPLE, work)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    r = _sh(python, "plan_and_run.py", cwd=work, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    assert r.stderr == ""
    lines = r.stdout.splitlines()
    assert lines[0] == "3 plans found in 47 expansions"
    # the three plans of the planning paper's Table 1: one action sequence, three grasps
    assert [line.split(" by ")[1] for line in lines[1:4]] == [
        "top_grasp",
        "side_grasp",
        "Method5Branch0",
    ]
    events = {line.split()[1] for line in lines[4:-1]}
    assert {"fault", "retrying", "replanned", "verified"} <= events
    assert lines[-1] == "verified: 8 of 8 steps verified, 3 retries, 1 replans"
    # the core install: no extra was there to be used
    check = _sh(
        python,
        "-c",
        "import importlib.util as u; "
        "print([m for m in ('pybullet', 'scipy', 'distributed') if u.find_spec(m)])",
        cwd=work,
        env=env,
    )
    assert check.stdout.strip() == "[]"


def test_the_api_page_shows_the_example_as_it_is():
    page = (ROOT / "docs" / "api.md").read_text()
    block = page.split("# Python API", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    code = EXAMPLE.read_text()
    assert code.startswith('"""') and block == code[code.index('"""\n', 3) + 4 :].lstrip("\n")


def test_the_readme_shows_the_example_the_getting_started_page_runs():
    """The README's short example is the one tests/e2e/test_guide.py runs from
    the getting-started page, character for character."""
    readme = (ROOT / "README.md").read_text()
    block = readme.split("## From Python", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    page = (ROOT / "docs" / "getting-started.md").read_text()
    ran = page.split("<!-- file: first.py -->\n```python\n", 1)[1].split("```", 1)[0]
    assert block == ran and len(block.splitlines()) <= 10
