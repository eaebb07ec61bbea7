"""How a command ends when it is told to: Ctrl-C, SIGTERM, a deadline, a closed pipe.

* SIGTERM is raised as :class:`Terminated`, a kind of ``KeyboardInterrupt``, so
  every path that cleans up after Ctrl-C (whole plans kept, temporary files
  removed, logs closed) does the same for a ``kill``. Its message, "stopped
  by SIGTERM", is the reason the task dispatcher logs.
* Every command ends an interrupt through :func:`interrupt_exit`: "interrupted"
  and exit code 130 for Ctrl-C, "terminated" and 143 for SIGTERM.
* ``htn run`` takes both with :class:`Signals`: during a tick of the behaviour
  tree they halt the task dispatcher, between ticks they interrupt at once.
* ``--timeout`` is a wall-clock :func:`deadline`: SIGALRM raises
  :class:`DeadlineExceeded` wherever the program is, also inside a user
  function or comparator that never returns (the planner's own check between
  expansions cannot see those). It is not an ``Exception``, so the user-code
  wrappers of :mod:`htn.jshop.language.functions` let it pass.
* Output units (a plan, a JSON line) are written with these signals held back
  (:func:`held`), so streams and files only ever contain whole units.

This module is imported by the entry point before anything else of ``htn``
(:mod:`htn.cli.start`): it imports only the standard library.
"""
from __future__ import annotations

import os
import signal
import sys
import time
from contextlib import contextmanager

INTERRUPT_EXIT = 128 + signal.SIGINT
SIGTERM_EXIT = 128 + signal.SIGTERM


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM: stop like Ctrl-C, exit code 143."""

    def __init__(self, reason: str = "stopped by SIGTERM"):
        super().__init__(reason)


class DeadlineExceeded(BaseException):
    """``--timeout`` ran out while the program was busy (e.g. in user code)."""


def interrupt(signum: int) -> KeyboardInterrupt:
    """The interrupt a signal stands for: :class:`Terminated` for SIGTERM,
    else ``KeyboardInterrupt`` (Ctrl-C)."""
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def interrupt_exit(exc: BaseException | None, note: str = "", now: bool = False):
    """End the process after the interrupt ``exc``: "terminated" (SIGTERM) or
    "interrupted" (anything else), then ``; note`` if given, on stderr; exit
    code 143 or 130. ``now``: leave at once (``os._exit``) instead of through
    the interpreter's shutdown, for a handler that runs while modules are
    being imported, and after PyBullet, whose shutdown after a Ctrl-C was
    seen (rarely) to end the process by SIGINT instead of the exit code."""
    terminated = isinstance(exc, Terminated)
    try:
        sys.stdout.flush()
    except (OSError, ValueError):       # the reader is gone (Ctrl-C on htn ... | less)
        silence_stdout()
    try:
        sys.stderr.write(("terminated" if terminated else "interrupted")
                         + (f"; {note}" if note else "") + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    code = SIGTERM_EXIT if terminated else INTERRUPT_EXIT
    if now:
        os._exit(code)
    sys.exit(code)


def silence_stdout() -> None:
    """Point stdout at /dev/null: the reader is gone, and Python's final
    flush must not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):   # no real file descriptor (tests capture stdout)
        pass


_RAISED: list = []     # the interrupts the handlers raised, see raise_again


def _raise_interrupt(signum, frame):
    exc = interrupt(signum)
    _RAISED.append(exc)
    raise exc


def raise_again() -> None:
    """Raise an interrupt once more if one was raised and the command goes on.

    Python ignores an exception raised while a finalizer runs (it prints
    "Exception ignored in ..."), and the search drops generators all the
    time: a Ctrl-C whose handler ran in one was lost, and ``htn plan --all``
    went on writing plans. A command calls this where it may stop (after
    each plan), so such a signal still ends it there."""
    if _RAISED:
        raise _RAISED[-1]


@contextmanager
def sigterm_as_interrupt():
    """While the block runs, Ctrl-C raises ``KeyboardInterrupt`` and SIGTERM
    :class:`Terminated`, each remembered for :func:`raise_again`."""
    _RAISED.clear()             # a new command (in-process callers run several)
    try:
        old = {sig: signal.signal(sig, _raise_interrupt)
               for sig in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:          # not the main thread: leave signals alone
        yield
        return
    # the signal mask as the caller had it: a command never leaves signals
    # blocked behind it (child processes inherit the mask, and a test
    # process that ran a command in-process would hand it to every later one)
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, ()) \
        if hasattr(signal, "pthread_sigmask") else None
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        if mask is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, mask)


class Signals:
    """Ctrl-C and SIGTERM while ``htn run`` runs. During a tick of the
    behaviour tree they halt the task dispatcher (the tick ends, the robot
    holds its pose, the log gets its summary); at any other time they raise
    their :func:`interrupt` at once, without a traceback. The task dispatcher
    turns one raised between its ticks (repair planning) into the same halt,
    with the same reason."""

    def __init__(self):
        self.received: KeyboardInterrupt | None = None   # the last interrupt
        self.dispatcher = None
        self.saved = {}
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                self.saved[sig] = signal.signal(sig, self._handle)
            except ValueError:     # not the main thread (a library caller)
                pass

    def _handle(self, signum, frame):
        self.received = exc = interrupt(signum)
        d = self.dispatcher
        if d is not None and d.in_tick:
            d.halt(str(exc))
            return
        raise exc

    def watch(self, dispatcher) -> None:
        """From now on a signal halts ``dispatcher`` during its ticks. One
        that came before interrupts now: Python drops an exception raised
        where it cannot propagate (in an import lock's callback), and the
        tree must not start after a swallowed Ctrl-C."""
        if self.received is not None:
            raise self.received
        self.dispatcher = dispatcher

    def ignore(self) -> None:
        for sig in self.saved:
            signal.signal(sig, signal.SIG_IGN)

    def restore(self) -> None:
        for sig, handler in self.saved.items():
            signal.signal(sig, handler)


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
    # the mask is read before it changes: an interrupt raised between the
    # blocking call and ``try`` would otherwise leave the signals blocked
    old = signal.pthread_sigmask(signal.SIG_BLOCK, ())
    try:
        signal.pthread_sigmask(signal.SIG_BLOCK, HELD)
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
