"""The watchdog: a stop (Ctrl-C, SIGTERM, ``--timeout``) that the program
does not act on is acted on for it.

It starts with the first stop a command's :class:`~htn.process.stops.Stops`
raises (only in htn's own process), as a daemon thread, and until the
command ends it

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
import atexit
import os
import sys
import threading
import time

GRACE = 3.0  # seconds user code gets to stop after a stop
HARD = 30.0  # seconds anything gets
EVERY = 0.2


class Watchdog:
    """Watches one command's stops (a :class:`~htn.process.stops.Stops`)."""

    def __init__(self, stops):
        self.stops = stops
        self.since = time.monotonic()
        self.done = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="htn-watchdog", daemon=True)

    def begin(self) -> Watchdog:
        self._thread.start()
        return self

    def cancel(self) -> None:
        """The command ended: nothing more to watch."""
        self.done.set()

    def _watch(self) -> None:
        while not self.done.wait(EVERY):
            signum = self.stops.signal_to_raise_again()
            if signum is not None and not self.done.is_set():
                _thread.interrupt_main(signum)
            waited = time.monotonic() - self.since
            stuck = self.stops.running_user_code()
            if stuck and waited >= GRACE:
                return self._end(f"{stuck} did not stop within {GRACE:g} s: ended")
            if waited >= HARD:
                return self._end(f"the command did not end within {HARD:g} s: ended")

    def _end(self, why: str) -> None:
        if not self.done.is_set():
            self.stops.emergency_exit(why)


_DEVNULL: list = []


def backstop_after(after: float) -> bool:
    """End the process (exit 1, nothing printed) ``after`` seconds from now
    even if no Python code can run: faulthandler's timer is a C thread."""
    import faulthandler

    if not _DEVNULL:
        _DEVNULL.append(open(os.devnull, "w"))
    faulthandler.dump_traceback_later(after, exit=True, file=_DEVNULL[0])
    return True


def cancel_backstop() -> None:
    import faulthandler

    faulthandler.cancel_dump_traceback_later()


def exit_code(code) -> int:
    """The exit code ``sys.exit(code)`` gives (None: 0; a message: printed, 1)."""
    if code is not None and not isinstance(code, int):
        try:
            sys.stderr.write(f"{code}\n")
        except (OSError, ValueError):
            pass
        return 1
    return code or 0


def leave_last(stops) -> None:
    """Register the exit hook that ends an owned process once its command
    has ended (``stops.exit_code`` is set): the other exit hooks (which
    remove temporaries) have run, but the interpreter's shutdown has not
    yet put the default signal handlers back, after which a signal would
    kill the process (an interrupted htn plan under load, 1 in 8; a finished
    htn run --sim). Exit hooks run last registered first: registered at the
    process's start, this one runs after those of every library imported."""

    def leave() -> None:
        if stops.exit_code is None:
            return
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(stops.exit_code)

    atexit.register(leave)
