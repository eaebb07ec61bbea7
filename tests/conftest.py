"""Shared fixtures: where the JSHOP2 corpus is, how to run ``htn`` (in this
process, or as a process of its own), and the markers of slow tests."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from inprocess import run_cli

ROOT = Path(__file__).resolve().parent.parent
SHARED = Path(os.environ.get("HTN_SHARED", ROOT.parent / "shared"))
CORPUS = SHARED / "corpus" / "jshop2"
FUNCTIONS = Path(__file__).resolve().parent / "functions"


def corpus_available() -> bool:
    return (CORPUS / "SUMMARY.md").is_file()


# a test that needs the JSHOP2 corpus (../shared): skipped without it, see
# pytest_collection_modifyitems
needs_corpus = pytest.mark.corpus


def htn_command(*args) -> list[str]:
    return [sys.executable, "-m", "htn", *map(str, args)]


def run_htn(*args, timeout=600, input=None, env=None):
    """Run the real command line (``htn ARGS``, from the checkout's root) in
    this process; returns a ``CompletedProcess`` with the exit code, stdout
    and stderr a subprocess would give (see :mod:`inprocess`). ``env``: the
    environment (default: this process's)."""
    return run_cli(*args, cwd=ROOT, env=env, input=input, timeout=timeout)


def run_htn_process(*args, timeout=600, input=None, env=None):
    """Run the real command line as ``python -m htn ARGS``, a process of its
    own (for tests about processes: signals, pipes, start-up, workers, file
    descriptors, interpreter settings); returns CompletedProcess."""
    return subprocess.run(
        htn_command(*args),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout,
        input=input,
        env=env,
    )


def start_htn(*args, **popen):
    """Start the real command line in a subprocess, stdout and stderr piped
    (text), without waiting for it; returns the Popen (to signal, read, kill)."""
    return subprocess.Popen(
        htn_command(*args),
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **popen,
    )


def wait_until(condition, what: str, proc=None, timeout: float = 60.0, every: float = 0.01):
    """Poll ``condition()`` until it is true. The test fails, naming ``what``,
    after ``timeout`` seconds or as soon as ``proc`` (if given) has ended;
    ``proc`` is killed then."""
    deadline = time.monotonic() + timeout
    while not condition():
        ended = proc is not None and proc.poll() is not None
        if ended or time.monotonic() > deadline:
            message = f"{what}: " + (
                "the process ended first" if ended else f"not within {timeout:g} s"
            )
            if proc is not None:
                proc.kill()
                _, err = proc.communicate()
                message += f" (exit code {proc.returncode}) {err or ''}"
            pytest.fail(message)
        time.sleep(every)


def interrupt_run(proc, sig: int, log: Path):
    """Send ``sig`` (SIGINT, SIGTERM) to a running ``htn run --log LOG``; it
    must end with exit code 128 + sig, without a traceback, and its log with
    the ``interrupted`` event and the summary. Returns stdout, stderr and the
    log's events."""
    proc.send_signal(sig)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, out + err
    assert "Traceback" not in err
    events = [json.loads(line) for line in log.read_text().splitlines()]  # all lines parse
    assert events[-2]["event"] == "interrupted"
    assert events[-1]["event"] == "summary" and events[-1]["result"] == "interrupted"
    return out, err, events


# The IPC 2020 competition's plan verifier (see shared/tools/pandaPIparser/README.md)
PANDA_PI = Path(os.environ.get("HTN_PANDAPI", SHARED / "tools" / "pandaPIparser" / "pandaPIparser"))


def pandapi_verify(domain, problem, plan) -> tuple:
    """The competition verifier's verdict on the IPC plan file ``plan``:
    ``(True or False, its output)``, or ``(None, why)`` without the binary.
    Any exit status but 0 is "not verified" (it crashes on some bad plans)."""
    if not PANDA_PI.is_file():
        return None, f"pandaPIparser not found at {PANDA_PI}"
    r = subprocess.run(
        [str(PANDA_PI), "-C", "--verify", str(domain), str(problem), str(plan)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    return r.returncode == 0 and "Plan verification result: true" in r.stdout, r.stdout


class IpcOracle:
    """Checks an IPC plan file with ``htn validate`` and, where the binary is
    there, with pandaPIparser as a second oracle: both must give ``valid``."""

    def __init__(self):
        self.missing = ""

    def check(self, domain, problem, plan, valid: bool = True):
        """Returns ``htn validate``'s CompletedProcess."""
        result = run_htn("validate", domain, problem, plan)
        assert "Traceback" not in result.stderr, result.stderr
        assert result.returncode == (0 if valid else 1), result.stdout + result.stderr
        verdict, out = pandapi_verify(domain, problem, plan)
        if verdict is None:
            self.missing = out
        else:
            assert verdict == valid, f"pandaPIparser's verdict is {verdict}:\n{out}"
        return result


@pytest.fixture
def ipc_oracle():
    """An :class:`IpcOracle`; without pandaPIparser the test is reported as
    skipped too (after its own checks have run), with the reason."""
    oracle = IpcOracle()
    yield oracle
    if oracle.missing:
        pytest.skip(f"{oracle.missing}: IPC plans checked by htn validate only")


@pytest.fixture(scope="session")
def checkout_wheel(tmp_path_factory) -> Path:
    """One wheel of this checkout for the whole run, shared by the xdist
    workers: pip builds it in the checkout's ``build/`` folder, so two
    builds at once collide (``File exists: build/bdist.../htn-0.1.0.dist-info``)."""
    import fcntl

    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent  # the run's folder, above each worker's
    folder = base / "checkout-wheel"
    with open(base / "checkout-wheel.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        wheels = list(folder.glob("htn-*.whl"))
        if not wheels:
            r = subprocess.run(
                [
                    sys.executable,
                    "-m",
                    "pip",
                    "wheel",
                    "-q",
                    "--no-deps",
                    "-w",
                    str(folder),
                    str(ROOT),
                ],
                cwd=base,
                capture_output=True,
                text=True,
                timeout=900,
            )
            assert r.returncode == 0, r.stdout + r.stderr
            wheels = list(folder.glob("htn-*.whl"))
    (wheel,) = wheels
    return wheel


GOLDEN = Path(__file__).resolve().parent / "golden"


def pytest_collection_modifyitems(config, items):
    """Tests marked ``corpus`` are skipped when the corpus is not there."""
    if corpus_available():
        return
    skip = pytest.mark.skip(
        reason=f"JSHOP2 corpus not found at {CORPUS} (set HTN_SHARED to the shared/ folder)"
    )
    for item in items:
        if item.get_closest_marker("corpus"):
            item.add_marker(skip)


def pytest_addoption(parser):
    parser.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="rewrite tests/golden/* from the current output instead of comparing",
    )


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
