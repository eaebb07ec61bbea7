"""Run the real ``htn`` command line in the test process.

:func:`run_cli` calls the entry point of ``python -m htn`` after its
start-up (:func:`htn.cli.main.main`, with the signal handlers
:mod:`htn.cli.start` leaves: Ctrl-C raises ``KeyboardInterrupt``, SIGTERM
has its default), with the arguments, working folder, environment and
standard input a subprocess would get, and returns what one returns: the
exit code and what was written to stdout and stderr. A test gets the same
answers as from ``python -m htn`` in about a hundredth of the time (no
interpreter start-up, no imports, PyBullet's and Dask's modules loaded once).

What a command may change in the process is put back after it, so that no
test sees another's: the working folder, ``os.environ``, ``sys.argv``, the
standard streams, the recursion limit, every logger's level and handlers,
the warning filters; compiled code is forgotten and temporary files removed
as at a process's end. What a command must put back itself (a library
caller relies on it) is checked first, and the test fails if it did not:
the signal handlers of SIGINT, SIGTERM, SIGALRM and SIGPIPE, the signal
mask (a blocked signal is inherited by every process started after) and the
interval timer of ``--timeout``.

What cannot happen in-process is refused, not imitated: an environment
that changes the interpreter's start-up (``PYTHON*``) or Dask's
configuration (``DASK_*``, read when Dask is imported). Tests about
processes (signals, closed pipes, start-up, installs, Dask workers, file
descriptors) use :func:`conftest.run_htn_process`.
"""

from __future__ import annotations

import io
import logging
import os
import signal
import subprocess
import sys
import threading
import traceback
import warnings
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
STARTUP_VARIABLES = ("PYTHON", "DASK_")  # read once, when a process or Dask starts
CHECKED_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGALRM, signal.SIGPIPE)


class LeakedState(AssertionError):
    """A command left process state behind that it must restore itself."""


def run_cli(*args, cwd=ROOT, env=None, input=None, timeout=600) -> subprocess.CompletedProcess:
    """``htn ARGS`` through the real entry point, in this process; a
    ``CompletedProcess`` as :func:`subprocess.run` (text mode) returns it.
    ``env`` replaces the environment, ``input`` is standard input;
    after ``timeout`` seconds the command gets a Ctrl-C and the test fails."""
    argv = [str(a) for a in args]
    if env is not None:
        _refuse_startup_changes(env)
    stdin = io.TextIOWrapper(io.BytesIO((input or "").encode("utf-8")), encoding="utf-8")
    stdout, stderr = _Pipe(), _Pipe(errors="backslashreplace")
    with _process_state(cwd, env, argv):
        sys.stdin, sys.stdout, sys.stderr = stdin, stdout.text, stderr.text
        timer = _Watchdog(timeout)
        try:
            code = _main(argv)
        finally:
            timer.cancel()
    if timer.fired:
        raise AssertionError(f"htn {' '.join(argv)} did not end within {timeout} s")
    return subprocess.CompletedProcess(["htn", *argv], code, stdout.read(), stderr.read())


class _Pipe(io.BytesIO):
    """What a command writes to stdout or stderr: text over bytes, as a
    pipe is (click and rich may write bytes to ``.buffer``), kept when the
    command closes the stream."""

    def __init__(self, errors: str = "strict"):
        super().__init__()
        self.kept = b""
        self.text = io.TextIOWrapper(
            self, encoding="utf-8", errors=errors, newline="\n", write_through=True
        )

    def close(self) -> None:
        if not self.closed:
            self.kept = self.getvalue()
        super().close()

    def read(self) -> str:
        """What was written, decoded as ``subprocess.run(text=True)`` does."""
        if not self.closed:
            try:
                self.text.flush()
            except ValueError:
                pass
        data = self.kept if self.closed else self.getvalue()
        return data.decode("utf-8", errors="replace").replace("\r\n", "\n").replace("\r", "\n")


def _main(argv: list[str]) -> int:
    """The exit code of ``htn ARGV``, as the interpreter would make it."""
    from htn.cli.main import main

    try:
        main(argv)
    except SystemExit as exc:
        if exc.code is None or isinstance(exc.code, int):
            return exc.code or 0
        print(exc.code, file=sys.stderr)
        return 1
    except KeyboardInterrupt:  # Python ends such a process by SIGINT
        traceback.print_exc()
        return -signal.SIGINT
    except BaseException:  # noqa: B036 - an uncaught error: a traceback, 1
        traceback.print_exc()
        return 1
    return 0


def _refuse_startup_changes(env: dict) -> None:
    changed = sorted(
        k
        for k in {*env, *os.environ}
        if k.startswith(STARTUP_VARIABLES) and env.get(k) != os.environ.get(k)
    )
    if changed:
        raise ValueError(
            f"{', '.join(changed)} take effect when a process starts: "
            "use run_htn_process for this test"
        )


class _Watchdog:
    """After ``seconds``, a Ctrl-C for the command (it then ends as htn
    ends on one), and the test fails."""

    def __init__(self, seconds):
        self.fired = False
        self.timer = None
        if seconds is not None:
            self.timer = threading.Timer(seconds, self._fire)
            self.timer.daemon = True
            self.timer.start()

    def _fire(self):
        import _thread

        self.fired = True
        _thread.interrupt_main()

    def cancel(self):
        if self.timer is not None:
            self.timer.cancel()


@contextmanager
def _process_state(cwd, env, argv):
    saved_cwd, saved_env = os.getcwd(), dict(os.environ)
    saved_argv, streams = sys.argv, (sys.stdin, sys.stdout, sys.stderr)
    saved_limit = sys.getrecursionlimit()
    saved_filters = warnings.filters[:]
    saved_loggers = _loggers()
    handlers = {sig: signal.getsignal(sig) for sig in CHECKED_SIGNALS}
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, ())
    leaks = []
    try:
        os.chdir(cwd)
        if env is not None:
            os.environ.clear()
            os.environ.update(env)
        sys.argv = [str(ROOT / "__main__.py"), *argv]
        # as htn.cli.start leaves them for main()
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        started = {sig: signal.getsignal(sig) for sig in CHECKED_SIGNALS}
        try:
            yield
        finally:
            leaks = _leaks(started, mask)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
        sys.stdin, sys.stdout, sys.stderr = streams
        sys.argv = saved_argv
        os.chdir(saved_cwd)
        if dict(os.environ) != saved_env:
            os.environ.clear()
            os.environ.update(saved_env)
        sys.setrecursionlimit(saved_limit)
        warnings.filters[:] = saved_filters
        _restore_loggers(saved_loggers)
        _as_at_exit()
    if leaks:
        raise LeakedState(f"htn {' '.join(argv)} left process state behind: " + "; ".join(leaks))


def _leaks(started: dict, mask: set) -> list[str]:
    leaks = []
    blocked = signal.pthread_sigmask(signal.SIG_BLOCK, ()) - mask
    if blocked:
        leaks.append("signals blocked: " + ", ".join(sorted(s.name for s in blocked)))
    for sig, handler in started.items():
        now = signal.getsignal(sig)
        if now != handler:
            leaks.append(f"{sig.name} handler {now!r} instead of {handler!r}")
    if signal.getitimer(signal.ITIMER_REAL)[0] > 0:
        leaks.append("an interval timer (SIGALRM) still runs")
    return leaks


def _loggers() -> dict:
    manager = logging.Logger.manager
    found = {"": logging.getLogger()}
    found.update(
        (n, lg) for n, lg in list(manager.loggerDict.items()) if isinstance(lg, logging.Logger)
    )
    return {n: (lg.level, lg.handlers[:], lg.propagate, lg.disabled) for n, lg in found.items()}


def _restore_loggers(saved: dict) -> None:
    # a logger first made by this command (a library imported) stays as
    # its import set it up, as in a process that imports it
    now = _loggers()
    for name, before in saved.items():
        if now.get(name, before) != before:
            logger = logging.getLogger(name or None)
            level, handlers, logger.propagate, logger.disabled = before
            logger.handlers[:] = handlers
            logger.setLevel(level)


def _as_at_exit() -> None:
    """What the end of a process does for htn: compiled code is gone, and
    its temporary files are removed (an atexit hook in a process)."""
    caches = sys.modules.get("htn.jshop.logic.caches")
    if caches is not None:
        caches.clear_caches()
    files = sys.modules.get("htn.files")  # AtomicFile's temporaries
    if files is not None:
        files._remove_pending()
