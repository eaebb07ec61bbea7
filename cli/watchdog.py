"""The watchdog: a stop (Ctrl-C, SIGTERM, ``--timeout``) that the program
does not act on is acted on for it.

It starts with the first stop :mod:`htn.cli.signals` raises, as a daemon
thread, and until the command ends it

* raises the stop again, every :data:`EVERY` seconds, while Python has
  dropped it (a stop raised inside a finalizer or a weakref callback is
  printed and forgotten, and the command would go on);
* ends the process :data:`GRACE` seconds after the stop if user code (a
  ``--functions`` function or comparator, or the file being loaded) is
  running then or later: it catches the stop and carries on. What is whole
  is kept first (the command's finalizers: plans written so far, a log's
  ``interrupted`` and ``summary`` events), the message names the function,
  and the exit code is the stop's (130, 143, or 1 for the deadline);
* ends it after :data:`HARD` seconds whatever runs (htn's own clean-up
  takes far less: this only bounds a hang).

This module imports only the standard library.
"""
from __future__ import annotations

import _thread
import os
import sys
import threading
import time
from typing import Callable, Optional

GRACE = 3.0      # seconds user code gets to stop after a stop
HARD = 30.0      # seconds anything gets
EVERY = 0.2


def running_user_code() -> Optional[str]:
    """What user code runs now (``function spin (funcs.py:3)``), if any."""
    functions = sys.modules.get("htn.jshop.language.functions")
    return functions.running_user_code() if functions is not None else None


class Watchdog:
    """``signal_of()``: the signal to raise a dropped stop again with (or
    None); ``end(why)``: keep what is whole and end the process."""

    def __init__(self, signal_of: Callable[[], Optional[int]], end: Callable[[str], None]):
        self.signal_of = signal_of
        self.end = end
        self.since = time.monotonic()
        self.done = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="htn-watchdog", daemon=True)

    def begin(self) -> "Watchdog":
        self._thread.start()
        return self

    def cancel(self) -> None:
        """The command ended: nothing more to watch."""
        self.done.set()

    def _watch(self) -> None:
        while not self.done.wait(EVERY):
            signum = self.signal_of()
            if signum is not None and not self.done.is_set():
                _thread.interrupt_main(signum)
            waited = time.monotonic() - self.since
            stuck = running_user_code()
            if stuck and waited >= GRACE:
                return self._end(f"{stuck} did not stop within {GRACE:g} s: ended")
            if waited >= HARD:
                return self._end(f"the command did not end within {HARD:g} s: ended")

    def _end(self, why: str) -> None:
        if not self.done.is_set():
            self.end(why)


_DEVNULL: list = []


def backstop_after(after: float) -> bool:
    """End the process (exit 1, nothing printed) ``after`` seconds from now
    even if no Python code can run: faulthandler's timer is a C thread."""
    import faulthandler
    if not _DEVNULL:
        _DEVNULL.append(open(os.devnull, "w"))
    faulthandler.dump_traceback_later(after, exit=True, file=_DEVNULL[0])
    return True


def leave_now(code) -> None:
    """Exit with ``code`` as ``sys.exit(code)`` would (None: 0; a message:
    printed, 1) but without the interpreter's shutdown (the exit hooks,
    which remove temporaries, run first): the shutdown puts the default
    signal handlers back, and a signal then kills the process (an
    interrupted htn plan under load, 1 in 8; a finished htn run --sim)."""
    import atexit
    atexit._run_exitfuncs()
    if code is not None and not isinstance(code, int):
        try:
            sys.stderr.write(f"{code}\n")
        except (OSError, ValueError):
            pass
        code = 1
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(code or 0)
