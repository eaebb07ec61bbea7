"""Shared fixtures: where the JSHOP2 corpus is, and how to run ``htn``."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("HTN_SHARED", ROOT.parent / "shared"))
CORPUS = SHARED / "corpus" / "jshop2"
FUNCTIONS = Path(__file__).resolve().parent / "functions"


def corpus_available() -> bool:
    return (CORPUS / "SUMMARY.md").is_file()


needs_corpus = pytest.mark.skipif(
    not corpus_available(),
    reason=f"JSHOP2 corpus not found at {CORPUS} (set HTN_SHARED to the shared/ folder)")


def run_htn(*args, timeout=600, input=None):
    """Run the real command line in a subprocess; returns CompletedProcess."""
    return subprocess.run([sys.executable, "-m", "htn", *map(str, args)],
                          cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                          input=input)

GOLDEN = Path(__file__).resolve().parent / "golden"


def pytest_addoption(parser):
    parser.addoption("--update-golden", action="store_true", default=False,
                     help="rewrite tests/golden/* from the current output instead of comparing")


@pytest.fixture
def golden(request):
    """``golden(name, text)``: compare ``text`` with tests/golden/name, byte for byte.

    The files are rewritten only when pytest runs with ``--update-golden``.
    """
    update = request.config.getoption("--update-golden")

    def check(name: str, text: str) -> None:
        path = GOLDEN / name
        if update:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
            return
        assert path.is_file(), f"missing golden file {path} (run pytest --update-golden)"
        assert text == path.read_text(), f"output differs from {path}"
    return check
