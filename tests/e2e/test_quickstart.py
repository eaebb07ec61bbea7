"""The README's quick start on a stock Debian/Ubuntu Python (issue 19): its two
commands' install steps, as written, in a copy of this checkout, with the
system's own ``/usr/bin/python3`` first on PATH (not another Python that may
come first here, as one did when the issue was found). A system Python
refuses ``pip install`` outside a virtualenv (PEP 668), so the commands must
make one, and what they install must be in it.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from conftest import ROOT

SYSTEM_PYTHON = Path("/usr/bin/python3")


def quick_start() -> list[str]:
    """The two commands of the README's quick start."""
    text = (ROOT / "README.md").read_text()
    start = text.index("## Quick start")
    section = text[start : text.index("\n## ", start + 1)]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    return [line for line in block.splitlines() if line.strip()]


def install_steps(command: str) -> str:
    """A command up to and including its ``pip install``."""
    parts = command.split(" && ")
    k = next(i for i, p in enumerate(parts) if p.startswith("pip install"))
    return " && ".join(parts[: k + 1])


def copy_checkout(to: Path) -> None:
    """The files of a clean clone: those git tracks (else all but builds)."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True)
    if listed.returncode == 0 and listed.stdout:
        for name in listed.stdout.decode().split("\0"):
            if name and (ROOT / name).is_file():
                (to / name).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(ROOT / name, to / name)
    else:
        shutil.copytree(
            ROOT,
            to,
            dirs_exist_ok=True,
            ignore=shutil.ignore_patterns(
                ".venv", "build", "dist", "*.egg-info", "__pycache__", ".git"
            ),
        )


def test_the_quick_start_commands_are_two_and_make_a_virtualenv():
    commands = quick_start()
    assert len(commands) == 2
    for command in commands:
        assert command.startswith("python3 -m venv .venv && . .venv/bin/activate && pip install ")
    assert "htn run plan.txt --sim" in commands[0]
    assert "python -m pytest -n 2 -v" in commands[1]


@pytest.mark.slow
@pytest.mark.skipif(not SYSTEM_PYTHON.is_file(), reason="no system /usr/bin/python3 here")
def test_the_quick_start_installs_with_the_system_python(tmp_path):
    probe = subprocess.run([SYSTEM_PYTHON, "-c", "import ensurepip, venv"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("the system python3 has no venv module (Debian: apt install python3-venv)")
    src = tmp_path / "checkout"  # not "htn": a folder of that name would be imported
    src.mkdir()
    copy_checkout(src)
    bin_ = tmp_path / "bin"
    bin_.mkdir()
    (bin_ / "python3").symlink_to(SYSTEM_PYTHON)
    env = {
        k: v
        for k, v in os.environ.items()
        if k not in ("VIRTUAL_ENV", "PYTHONPATH", "PYTHONHOME", "PYTHONUSERBASE")
    }
    env["PATH"] = f"{bin_}:/usr/bin:/bin"
    for command in quick_start():
        steps = install_steps(command)
        r = subprocess.run(
            ["bash", "-c", steps], cwd=src, env=env, capture_output=True, text=True, timeout=3600
        )
        assert r.returncode == 0, f"{steps}\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}"
    python = src / ".venv" / "bin" / "python"
    # the virtualenv is the system Python's, and holds what both commands need
    r = subprocess.run(
        [
            python,
            "-c",
            "import sys, htn, pybullet, pytest, xdist, hypothesis; "
            "print(sys.base_prefix); print(htn.__file__)",
        ],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    base, where = r.stdout.split()
    assert base == "/usr"
    assert where.startswith(str(src / ".venv"))
    # and the first command's planning step runs from it
    r = subprocess.run(
        [
            "bash",
            "-c",
            ". .venv/bin/activate && htn plan domains/domestic.jshop "
            "problems/bring_object.jshop -o plan.txt",
        ],
        cwd=src,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    assert (src / "plan.txt").read_text().count("(!") == 8
