"""The signal handlers of a command, and of the process around it.

* :func:`begin_process`: htn's entry point's first act (after its own early
  handlers): until a command takes over, and again once it has ended (while
  the interpreter shuts down), a signal ends the process at once:
  ``interrupted`` (Ctrl-C) or ``terminated`` (SIGTERM), exit code 130 or 143.
* :func:`command`: while a command runs, SIGINT raises ``KeyboardInterrupt``
  and SIGTERM :class:`~htn.process.stops.Terminated` (a kind of it), so
  every clean-up after Ctrl-C is done for a ``kill`` too. Only the first
  signal is raised (a second must not break the clean-up); any signal still
  decides the exit code. The caller's handlers come back after it.
* :func:`deadline`: ``--timeout`` as a wall-clock timer (SIGALRM).
* :func:`end_process`: the entry point's last act.

A library that embeds :mod:`htn.api` installs none of these unless it calls
them: the use cases stop by their own ``timeout`` and the ``stops`` they are
given.
"""

from __future__ import annotations

import signal
import sys
import time
from contextlib import contextmanager

from htn.jshop.language.errors import is_stop

from .stops import (
    COMMAND,
    EXIT,
    START,
    DeadlineExceeded,
    Stops,
    TimedOut,
    flush_stdout,
    interrupt,
    timeout_reason,
)
from .watchdog import GRACE, backstop_after, cancel_backstop, exit_code, leave_last

MAX_TIMER = 1e8  # seconds (three years): a longer --timeout is no limit
AGAIN = 0.5  # seconds: the deadline is raised again until the command stops


def _on_signal(stops: Stops):
    def handler(signum, frame):
        exc = interrupt(signum)
        if stops.received is None:
            stops.received = exc
        if stops.phase != COMMAND:
            stops.interrupt_exit(stops.received, now=True)
        stops.deliver(exc)

    return handler


def begin_process(stops: Stops) -> None:
    """From now on a signal ends the process at once, until a
    :func:`command` takes over (and again after it). ``stops`` is the
    process's own (``Stops(owned=True)``)."""
    stops.phase = START
    leave_last(stops)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _on_signal(stops))


@contextmanager
def command(stops: Stops | None = None):
    """Run a command under ``stops`` (a new one if None); see the module's
    docstring. Yields the :class:`Stops`."""
    stops = stops if stops is not None else Stops()
    stops.reset()
    stops.phase = COMMAND
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, ())  # put back after (user code)
    handler = _on_signal(stops)
    try:
        old = {sig: signal.signal(sig, handler) for sig in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:  # not the main thread: leave signals alone
        old = {}

    def unraisable(args) -> None:
        # a stop raised in a finalizer or a weakref callback is dropped by
        # Python (with a traceback on stderr): remember it, the watchdog
        # raises it again
        if is_stop(args.exc_value):
            stops.swallowed = True
            return
        hook(args)

    hook, sys.unraisablehook = sys.unraisablehook, unraisable
    try:
        yield stops
    finally:
        if stops.owned:
            stops.phase = EXIT  # first: a signal from now on ends the process at once
        if stops.watchdog is not None:
            stops.watchdog.cancel()
        sys.unraisablehook = hook
        for sig, old_handler in old.items():
            signal.signal(sig, old_handler)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def end_process(stops: Stops, code) -> None:
    """Exit with ``code``, or 130/143 if a signal came that the command did
    not report. In an owned process the exit hooks run, and the last of
    them leaves with the code (:func:`htn.process.watchdog.leave_last`)."""
    stops.phase = EXIT
    if stops.received is not None and not stops.reported:
        stops.interrupt_exit(stops.received)
    flush_stdout()
    if stops.owned:
        stops.exit_code = exit_code(code)
        sys.exit(stops.exit_code)
    sys.exit(code)


def _on_alarm(stops: Stops):
    def handler(signum, frame):
        # again until the deadline's block ends: Python drops an exception
        # raised in a finalizer, and even a library caller's command must stop
        if stops.halting is None:  # a run ends by being halted, once
            signal.setitimer(signal.ITIMER_REAL, AGAIN)
            if isinstance(stops.raised, DeadlineExceeded) and not stops.swallowed:
                stops.swallowed = True  # raised before and the command goes on: again
        stops.deliver(
            TimedOut(timeout_reason(stops.timeout))
            if stops.halting is not None
            else DeadlineExceeded()
        )

    return handler


@contextmanager
def deadline(stops: Stops, seconds: float | None, started: float | None = None):
    """Raise :class:`DeadlineExceeded` (into a watched run: halt it with
    :class:`TimedOut`) once ``seconds`` have passed since ``started`` (a
    ``time.perf_counter()`` value; default: now). None (or more than
    :data:`MAX_TIMER`): no limit. If code that holds the interpreter (a C
    extension) keeps the handler from running at all, an owned process ends
    with exit code 1 ``GRACE`` + 2 seconds after the deadline."""
    if seconds is None or seconds > MAX_TIMER:
        yield
        return
    remaining = seconds - (time.perf_counter() - started if started is not None else 0.0)
    try:
        old = signal.signal(signal.SIGALRM, _on_alarm(stops))
    except ValueError:  # not the main thread: the planner's own check must do
        yield
        return
    outer, stops.timeout = stops.timeout, seconds
    signal.setitimer(signal.ITIMER_REAL, max(remaining, 1e-3))
    # a library caller's process is not ours to end
    backstop = stops.owned and backstop_after(max(remaining, 0.0) + GRACE + 2.0)
    try:
        yield
    finally:
        while True:
            try:
                signal.setitimer(signal.ITIMER_REAL, 0)
                break
            except DeadlineExceeded:  # raised again as it was being cancelled
                continue
        if backstop:
            cancel_backstop()
        signal.signal(signal.SIGALRM, old)
        stops.timeout = outer if outer is not None else stops.timeout
