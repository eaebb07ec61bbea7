"""The browser view as a new user installs it: a wheel in a fresh virtualenv,
first without the view extra (the commands say which extra they need), then
with it (the page and every asset it names come from the installed package)."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import urllib.request
from pathlib import Path

import pytest

from conftest import ROOT

STATIC = ROOT / "view" / "static"


def sh(*args, cwd, env=None, **popen):
    return subprocess.run(
        [str(a) for a in args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=900,
        env=env,
        **popen,
    )


def test_no_asset_of_the_page_comes_from_elsewhere():
    for path in STATIC.iterdir():
        text = path.read_text(encoding="utf-8")
        assert not re.search(
            r"(https?:)?//[\w.-]+\.[a-z]{2,}/", text.replace("http://www.w3.org/2000/svg", "")
        ), path  # the SVG namespace is no address


@pytest.mark.slow
def test_the_view_extra_installs_the_page(tmp_path, checkout_wheel):
    wheel = checkout_wheel
    venv = tmp_path / "venv"
    assert sh(sys.executable, "-m", "venv", venv, cwd=tmp_path).returncode == 0
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"

    def pip(*a):
        return sh(venv / "bin" / "python", "-m", "pip", "install", "-q", *a, cwd=tmp_path, env=env)

    assert pip(wheel).returncode == 0
    work = tmp_path / "work"
    work.mkdir()
    htn = lambda *a: sh("htn", *a, cwd=work, env=env)  # noqa: E731
    assert htn("examples", ".").returncode == 0
    r = htn("plan", "domains/domestic.jshop", "problems/bring_object.jshop", "-o", "plan.txt")
    assert r.returncode == 0, r.stderr
    r = htn("run", "plan.txt", "--robot", "symbolic", "--log", "run.jsonl")
    assert r.returncode == 0, r.stderr
    r = htn("run", "plan.txt", "--robot", "symbolic", "--view")
    assert r.returncode == 2
    assert r.stderr == "htn run --view needs the view extra: pip install 'htn[view]'\n"
    r = htn("view", "run.jsonl")
    assert r.returncode == 2
    assert r.stderr == "htn view needs the view extra: pip install 'htn[view]'\n"
    r = pip(f"{wheel}[view]")
    assert r.returncode == 0, r.stderr
    proc = subprocess.Popen(
        ["htn", "view", "run.jsonl"],
        cwd=work,
        env=env,
        text=True,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        url = re.fullmatch(r"view: (\S+)\n", proc.stderr.readline()).group(1)
        with urllib.request.urlopen(url, timeout=30) as response:
            page = response.read().decode()
        assets = re.findall(r'(?:src|href)="(static/[^"]+)"', page)
        assert {Path(a.split("?")[0]).name for a in assets} >= {
            "app.js",
            "tree.js",
            "timeline.js",
            "style.css",
            "favicon.svg",
        }
        base = url.split("?")[0]
        for asset in assets:
            with urllib.request.urlopen(base + asset.replace("&amp;", "&"), timeout=30) as response:
                name = asset.split("?")[0]
                assert response.read() == (ROOT / "view" / name).read_bytes(), name
    finally:
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
    assert proc.returncode == 0
