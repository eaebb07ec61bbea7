"""docs/guide.md and docs/getting-started.md, run as a newcomer would: its commands, in order, from a folder
outside the checkout, in a fresh virtualenv (issue 19).

The guide marks what is run. ``<!-- file: PATH -->`` before a fenced block:
the block is written to PATH. ``<!-- run -->`` (or ``<!-- run: exit N -->``)
before a ``sh`` block: the block is run with bash, and must end with exit
code 0 (or N). ``<!-- output -->`` before a ``text`` block: each of its lines
must be in what the run before it printed. So the guide and this test cannot
drift apart.

The virtualenv is made with this interpreter's site-packages as a site
directory (the like of ``--system-site-packages``, which from inside a
virtualenv would give the base interpreter's), so that htn's dependencies
need no download; htn itself is installed from a wheel of this checkout, and
the guide's plugin with pip, from its folder.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from coffee import COFFEE, COFFEE_HDDL, MORNING, MORNING_HDDL
from conftest import ROOT

GUIDE = ROOT / "docs" / "guide.md"
GETTING_STARTED = ROOT / "docs" / "getting-started.md"
MARK = re.compile(
    r"<!-- (file: (?P<file>\S+)|run(: exit (?P<exit>\d+))?|output) -->\n"
    r"```[a-z]*\n(?P<body>.*?)```\n",
    re.S,
)


def guide_blocks(text: str) -> list[tuple[str, str, str]]:
    """The marked blocks in order: ("file", path, text), ("run", exit code,
    commands), ("output", "", expected lines)."""
    out = []
    for m in MARK.finditer(text):
        if m.group("file"):
            out.append(("file", m.group("file"), m.group("body")))
        elif m.group(0).startswith("<!-- run"):
            out.append(("run", m.group("exit") or "0", m.group("body")))
        else:
            out.append(("output", "", m.group("body")))
    return out


def test_the_guide_marks_its_blocks_and_shows_the_tested_coffee_robot():
    blocks = guide_blocks(GUIDE.read_text())
    files = {path: body for kind, path, body in blocks if kind == "file"}
    # the domain the guide writes is the one the error and retry tests use
    assert files["coffee.jshop"] == COFFEE and files["morning.jshop"] == MORNING
    assert files["coffee.hddl"] == COFFEE_HDDL and files["morning.hddl"] == MORNING_HDDL
    runs = [b for b in blocks if b[0] == "run"]
    assert len(runs) >= 10
    # every output block follows a run block
    assert all(blocks[k - 1][0] == "run" for k, b in enumerate(blocks) if b[0] == "output")
    # every fenced sh block is marked to be run (a command the test skips can drift)
    assert GUIDE.read_text().count("```sh\n") == len(runs)


@pytest.fixture(scope="module")
def venv(tmp_path_factory, checkout_wheel) -> Path:
    """A fresh virtualenv with htn from a wheel of this checkout, its
    dependencies seen from this interpreter's site-packages."""
    base = tmp_path_factory.mktemp("venv")
    venv = base / "venv"
    assert subprocess.run([sys.executable, "-m", "venv", venv], timeout=600).returncode == 0
    site = Path(
        subprocess.run(
            [
                venv / "bin" / "python",
                "-c",
                "import sysconfig; print(sysconfig.get_paths()['purelib'])",
            ],
            capture_output=True,
            text=True,
        ).stdout.strip()
    )
    here = sysconfig.get_paths()["purelib"]
    (site / "htn-test-parent-site.pth").write_text(f"import site; site.addsitedir({here!r})\n")
    wheel = checkout_wheel
    # --ignore-installed: the parent site may hold htn of the same version (a
    # non-editable install, as CI makes), and pip would then skip the wheel and
    # leave the venv without its own htn and htn command.
    r = subprocess.run(
        [
            venv / "bin" / "python",
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--ignore-installed",
            wheel,
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert (venv / "bin" / "htn").is_file()
    return venv


def run_page(page: Path, venv: Path, work: Path) -> None:
    """A page's marked blocks, in order, in WORK with VENV's htn on PATH."""
    assert ROOT not in work.parents
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    env["VIRTUAL_ENV"] = str(venv)
    printed = ""
    for kind, what, body in guide_blocks(page.read_text()):
        if kind == "file":
            path = work / what
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(body)
        elif kind == "run":
            r = subprocess.run(
                ["bash", "-c", body], cwd=work, env=env, capture_output=True, text=True, timeout=900
            )
            printed = r.stdout + r.stderr
            assert r.returncode == int(what), f"{body}\nexit {r.returncode}:\n{printed}"
            assert "Traceback" not in printed, printed
        else:
            for line in filter(None, (x.strip() for x in body.splitlines())):
                assert line in printed, f"{line!r} not in:\n{printed}"


@pytest.mark.slow
def test_the_guide_runs_from_a_folder_outside_the_checkout(venv, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    run_page(GUIDE, venv, work)
    assert (work / "plan.txt").is_file() and (work / "run.jsonl").is_file()


def test_the_getting_started_page_marks_every_command_it_shows():
    text = GETTING_STARTED.read_text()
    blocks = guide_blocks(text)
    runs = [b for b in blocks if b[0] == "run"]
    assert len(runs) >= 6 and text.count("```sh\n") == len(runs)
    assert [p for k, p, _ in blocks if k == "file"] == ["first.py"]


@pytest.mark.slow
def test_the_getting_started_page_runs_from_a_folder_outside_the_checkout(venv, tmp_path):
    work = tmp_path / "work"
    work.mkdir()
    run_page(GETTING_STARTED, venv, work)
    assert (work / "plan.txt").is_file() and (work / "run.jsonl").is_file()
    assert (work / "domains" / "domestic.jshop").is_file()
