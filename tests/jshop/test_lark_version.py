"""htn reads with lark 1.x and with lark-parser 0.12, the same module under
an older name, which ROS 2's wheels (the ros extra) bring and which pip
installs over lark 1.x's files in a virtualenv that has both; an older
lark is one clear error, not a failure deep in the parser."""

from __future__ import annotations

import os
import subprocess
import sys

import lark
import pytest

from htn.jshop.language.errors import HtnError
from htn.jshop.readers import hddl, jshop2, lark_errors

from conftest import ROOT, SHARED, htn_command


@pytest.mark.parametrize("version", ["0.11.3", "0.7.8", "unknown"])
def test_a_lark_older_than_0_12_is_named_with_the_fix(monkeypatch, version):
    monkeypatch.setattr(lark, "__version__", version)
    with pytest.raises(HtnError, match=r"pip install --force-reinstall --no-deps 'lark>=1\.1\.9'"):
        lark_errors.check_lark()


def test_both_readers_check_before_they_build_their_parser(monkeypatch):
    monkeypatch.setattr(lark, "__version__", "0.11.0")
    for reader in (jshop2, hddl):
        reader._lark.cache_clear()
        with pytest.raises(HtnError, match="older than htn reads with"):
            reader._lark()
        reader._lark.cache_clear()


@pytest.mark.parametrize("version", ["0.12.0", "1.1.9", "1.3.1"])
def test_lark_0_12_and_1_pass(monkeypatch, version):
    monkeypatch.setattr(lark, "__version__", version)
    lark_errors.check_lark()


@pytest.mark.slow
def test_the_readers_give_the_same_plans_and_errors_under_the_real_lark_parser_0_12(tmp_path):
    """lark-parser 0.12 from the package registry, first on the path: the same
    JSHOP2 and HDDL plans and the same located syntax errors as lark 1.x."""
    target = tmp_path / "lark012"
    got = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--target",
            str(target),
            "lark-parser==0.12.0",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    if got.returncode != 0:
        pytest.skip(f"lark-parser 0.12 could not be installed: {got.stderr.strip()[-300:]}")
    bad = tmp_path / "bad.jshop"
    bad.write_text(
        (ROOT / "problems" / "bring_object.jshop")
        .read_text()
        .replace("(robot jenny)", "(robot jenny", 1)
    )
    hddl_domain = SHARED / "corpus" / "ipc2020-to" / "Childsnack" / "domain.hddl"
    commands = [
        ("plan", ROOT / "domains" / "domestic.jshop", ROOT / "problems" / "bring_object.jshop"),
        ("plan", ROOT / "domains" / "kitchen.jshop", ROOT / "problems" / "tray_three.jshop"),
        ("plan", ROOT / "domains" / "domestic.jshop", bad),
    ]
    if hddl_domain.is_file():  # the IPC corpus in ../shared, where it is
        commands.append(("plan", hddl_domain, hddl_domain.parent / "p05.hddl"))
    for args in commands:
        runs = {}
        for version, path in (("1.x", ""), ("0.12", str(target))):
            env = {**os.environ, "PYTHONPATH": path} if path else dict(os.environ)
            probe = subprocess.run(
                [sys.executable, "-c", "import lark; print(lark.__version__)"],
                env=env,
                capture_output=True,
                text=True,
                cwd=tmp_path,
            )
            assert probe.stdout.startswith("0.12" if path else "1."), probe
            r = subprocess.run(
                htn_command(*args),
                env=env,
                capture_output=True,
                text=True,
                cwd=tmp_path,
                timeout=300,
            )
            runs[version] = (r.returncode, r.stdout, r.stderr)
        assert runs["0.12"] == runs["1.x"], args
        assert runs["1.x"][0] in (0, 2) and "Traceback" not in runs["1.x"][2]
