"""How a command ends when it is told to: SIGTERM, a deadline, a closed pipe.

* SIGTERM is raised as :class:`Terminated`, a kind of ``KeyboardInterrupt``, so
  every path that cleans up after Ctrl-C (whole plans kept, temporary files
  removed, logs closed) does the same for a ``kill``; the exit code is 143.
* ``--timeout`` is a wall-clock :func:`deadline`: SIGALRM raises
  :class:`DeadlineExceeded` wherever the program is, also inside a user
  function or comparator that never returns (the planner's own check between
  expansions cannot see those). It is not an ``Exception``, so the user-code
  wrappers of :mod:`htn.jshop.functions` let it pass.
* Output units (a plan, a JSON line) are written with these signals held back
  (:func:`held`), so streams and files only ever contain whole units.
"""
from __future__ import annotations

import signal
import time
from contextlib import contextmanager

SIGTERM_EXIT = 128 + signal.SIGTERM


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM: stop like Ctrl-C, exit code 143."""


class DeadlineExceeded(BaseException):
    """``--timeout`` ran out while the program was busy (e.g. in user code)."""


def _raise_terminated(signum, frame):
    raise Terminated()


@contextmanager
def sigterm_as_interrupt():
    """Turn SIGTERM into :class:`Terminated` while the block runs."""
    try:
        old = signal.signal(signal.SIGTERM, _raise_terminated)
    except ValueError:          # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _raise_deadline(signum, frame):
    # a user function that swallowed the first one gets another in a second
    signal.setitimer(signal.ITIMER_REAL, 1.0)
    raise DeadlineExceeded()


@contextmanager
def deadline(seconds: float | None, started: float | None = None):
    """Raise :class:`DeadlineExceeded` once ``seconds`` have passed since
    ``started`` (a ``time.perf_counter()`` value; default: now). None: no limit."""
    if seconds is None:
        yield
        return
    remaining = seconds - (time.perf_counter() - started if started is not None else 0.0)
    try:
        old = signal.signal(signal.SIGALRM, _raise_deadline)
    except ValueError:          # not the main thread: the planner's own check must do
        yield
        return
    signal.setitimer(signal.ITIMER_REAL, max(remaining, 1e-3))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


HELD = {signal.SIGINT, signal.SIGTERM, signal.SIGALRM}


@contextmanager
def held():
    """Hold back Ctrl-C, SIGTERM and the deadline while a unit of output is
    written; a signal that came meanwhile arrives right after."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, HELD)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
