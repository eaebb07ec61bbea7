"""One command's stops: Ctrl-C, SIGTERM, the ``--timeout`` deadline.

A :class:`Stops` is made by :func:`htn.process.handlers.command` for one
command and passed down to what the command runs: the use cases take it as
``stops=`` (the user functions run under it, see :meth:`Stops.enter`), the
command line's commands find it in click's context. Nothing about stopping
is kept in a module: a library that runs several commands, in several
threads, gets one object per command and no process-wide state.

What happens to a stop (the module docstring of :mod:`htn.process` tells
the whole story):

* raised into the program at once (``KeyboardInterrupt``, :class:`Terminated`,
  :class:`DeadlineExceeded`), marked as htn's own (:func:`mark_stop`);
* held while a unit of output is written (:meth:`Stops.held`), raised when
  it is whole;
* turned into a halt of the run that is :meth:`watch`\\ ed, when it comes
  during one of its ticks;
* only recorded once the command ends in order (:meth:`settle`);
* raised again if user code swallowed it (:meth:`dropped`, and the
  watchdog for a stop Python itself dropped).
"""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable
from contextlib import contextmanager
from typing import TYPE_CHECKING, Protocol

from htn.jshop.language.errors import is_stop, mark_stop

if TYPE_CHECKING:
    from htn.jshop.language.functions import Guard as _Guard

    from .watchdog import Watchdog
else:
    # a Stops is the Guard user code runs under (htn.jshop.language.functions),
    # to the type checker; at run time that module is not imported at start-up
    _Guard = object

INTERRUPT_EXIT = 128 + signal.SIGINT
SIGTERM_EXIT = 128 + signal.SIGTERM
TIMEOUT_EXIT = 1

START, COMMAND, EXIT = "start", "command", "exit"


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM: stop like Ctrl-C, exit code 143."""

    def __init__(self, reason: str = "stopped by SIGTERM"):
        super().__init__(reason)


class DeadlineExceeded(BaseException):
    """``--timeout`` ran out while the program was busy (e.g. in user code)."""


class TimedOut(KeyboardInterrupt):
    """``--timeout`` ran out during ``htn run``: the run stops like after
    Ctrl-C (the log ends ``interrupted``, with this reason), exit code 1."""


class Haltable(Protocol):
    """What a stop can halt instead of raising into it (a run of
    :class:`htn.api.run.Execution`)."""

    def halt(self, why: str = "") -> bool:
        """Halt; True if the halt takes effect by itself (a tick is running
        and ends first), False if the caller must raise its stop too."""


def interrupt(signum: int) -> KeyboardInterrupt:
    """The interrupt a signal stands for: :class:`Terminated` for SIGTERM,
    else ``KeyboardInterrupt`` (Ctrl-C)."""
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def timeout_reason(seconds) -> str:
    return f"--timeout {seconds:g} s ran out" if seconds is not None else "--timeout ran out"


class Stops(_Guard):
    """The stops of one command. ``owned``: htn's own entry point runs the
    process (:mod:`htn.cli.start`), so a stop may end it (``os._exit``) and a
    watchdog thread may interrupt it; a library caller's process is neither."""

    def __init__(self, owned: bool = False):
        self.owned = owned
        self.phase = COMMAND  # START and EXIT only in an owned process
        self.count = 0  # stops raised into the program so far
        self.running: list[str] = []  # user code running now (innermost last)
        self.raised_last: BaseException | None = None
        self.exit_code: int | None = None  # set when an owned process leaves
        self.reset()

    def reset(self) -> None:
        self.received: BaseException | None = None  # the first SIGINT / SIGTERM
        self.raised: BaseException | None = None  # the stop raised into the program
        self.swallowed = False  # ... and dropped where Python cannot let it out
        self.quiet = False  # record signals only: the command ends in order
        self.holding = 0
        self.pending: BaseException | None = None  # came during a held() block
        self.halting: Haltable | None = None  # halted instead of raised into
        self.timeout: float | None = None  # the --timeout in force (seconds)
        self.reported = False  # "interrupted" was printed
        self.started = time.perf_counter()
        self.watchdog: Watchdog | None = None
        self.finalizers: list[Callable[[], str | None]] = []

    # ------------------------------------------------------------ raising a stop
    def raise_(self, exc: BaseException) -> BaseException:
        """``exc`` marked as htn's own stop and counted; the caller raises it."""
        self.count += 1
        self.raised_last = exc
        return mark_stop(exc)

    def deliver(self, exc: BaseException) -> None:
        """Raise ``exc`` into the program now, later (held, halted) or not at all."""
        if self.holding:
            if self.pending is None or isinstance(self.pending, DeadlineExceeded):
                self.pending = exc  # an interrupt outranks the deadline
            return
        if self.quiet or (self.raised is not None and not self.swallowed):
            return  # the command is stopping already
        self.swallowed = False
        self.raised = exc
        if self.watchdog is None and self.owned:
            # only in htn's own process: a library caller's (or a test's)
            # process is not ours to interrupt from another thread, nor to end
            from .watchdog import Watchdog

            self.watchdog = Watchdog(self).begin()
        if self.halting is not None and self.halting.halt(str(exc)):
            return
        raise self.raise_(exc)

    def signal_to_raise_again(self) -> int | None:
        """The signal to raise a swallowed stop again with (None: none swallowed)."""
        if not self.swallowed or self.raised is None:
            return None
        if isinstance(self.raised, (DeadlineExceeded, TimedOut)):
            return signal.SIGALRM
        return signal.SIGTERM if isinstance(self.raised, Terminated) else signal.SIGINT

    # ------------------------------------------------------------ user code
    def enter(self, what: str) -> int:
        """User code (``what``: ``function spin``) starts: the watchdog may
        name it; the token tells :meth:`dropped` what came since."""
        self.running.append(what)
        return self.count

    def leave(self, token: object) -> None:
        self.running.pop()

    def dropped(self, token: object) -> BaseException | None:
        """A stop raised since :meth:`enter` returned ``token`` that the user
        code caught (and dropped, or turned into its own): raise it again."""
        if self.count != token and self.raised_last is not None:
            return self.raise_(self.raised_last)
        return None

    def running_user_code(self) -> str | None:
        return self.running[-1] if self.running else None

    # ------------------------------------------------------------ during a command
    @contextmanager
    def held(self):
        """Hold back Ctrl-C, SIGTERM and the deadline while a unit of output
        is written; one that came meanwhile is raised right after."""
        self.holding += 1
        try:
            yield
        finally:
            self.holding -= 1
            if not self.holding and self.pending is not None:
                exc, self.pending = self.pending, None
                self.deliver(exc)

    def raise_again(self) -> None:
        """Raise the stop once more if Python dropped it (it was raised in a
        finalizer: the search drops generators all the time) and the command
        goes on. A command calls this where it may stop (after each plan)."""
        if self.swallowed and self.raised is not None:
            self.swallowed = False
            raise self.raise_(self.raised)

    def watch(self, target: Haltable) -> None:
        """From now on a stop halts ``target`` (during its ticks) instead of
        being raised. One that came before raises now: the run must not
        start after a Ctrl-C that was swallowed."""
        if self.raised is not None:
            raise self.raise_(self.raised)
        self.halting = target

    def settle(self) -> None:
        """From now on signals are only recorded (they set the exit code):
        the command ends in order (``htn run`` after its summary)."""
        self.halting = None
        self.quiet = True

    def listen_again(self) -> None:
        """Signals raise again (``htn run --view`` keeps its page up until
        Ctrl-C); one that came while they were only recorded raises now."""
        self.quiet = False
        self.raised, self.swallowed = None, False
        if self.received is not None:
            exc, self.received = self.received, None
            raise self.raise_(exc)

    def consume(self) -> None:
        """The signal that came ends the command normally (``htn view``:
        Ctrl-C is how a server stops), not with 130/143."""
        self.received = None

    def on_emergency(self, finalizer: Callable[[], str | None]) -> None:
        """``finalizer()`` (returning a note or None) keeps what is whole if
        the watchdog has to end the process (:mod:`htn.process.watchdog`)."""
        self.finalizers.append(finalizer)

    @property
    def cause(self) -> BaseException | None:
        """The stop that ends the command: the signal received, else the one raised."""
        return self.received or self.raised

    # ------------------------------------------------------------ ending
    def exit_of(self, exc) -> tuple[int, str]:
        """The exit code and the word a stop ends a command with."""
        if isinstance(exc, Terminated):
            return SIGTERM_EXIT, "terminated"
        if isinstance(exc, (TimedOut, DeadlineExceeded)):
            seconds = self.timeout
            return TIMEOUT_EXIT, "timed out" + (f" after {seconds:g} s" if seconds else "")
        return INTERRUPT_EXIT, "interrupted"

    def interrupt_exit(self, exc: BaseException | None, note: str = "", now: bool = False):
        """End the command after the stop ``exc``: "terminated" (SIGTERM),
        "timed out" (the deadline) or "interrupted" (anything else), then
        ``; note`` if given, on stderr; exit code 143, 1 or 130. ``now``:
        leave at once (``os._exit``) instead of through the interpreter's
        shutdown, for a handler that runs while modules are imported or the
        interpreter shuts down, and after PyBullet, whose shutdown after a
        Ctrl-C was seen (rarely) to end the process by SIGINT instead of
        the exit code. Only in an owned process: else ``SystemExit``."""
        if self.received is not None and isinstance(exc, (TimedOut, DeadlineExceeded)):
            exc = self.received  # a signal came too: it decides
        self.reported = True
        code, word = self.exit_of(exc)
        flush_stdout()
        try:
            sys.stderr.write(word + (f"; {note}" if note else "") + "\n")
            sys.stderr.flush()
        except (OSError, ValueError):
            pass
        if now and self.owned:
            os._exit(code)
        sys.exit(code)

    def emergency_exit(self, stuck: str) -> None:
        """The watchdog's end: keep what is whole (the finalizers), say why,
        leave with the stop's exit code."""
        if not self.owned:  # a library caller's process is not ours to end
            return
        waited = time.monotonic()
        while self.holding and time.monotonic() - waited < 1.0:  # a unit being written
            time.sleep(0.01)
        notes = [stuck]
        for finalizer in reversed(self.finalizers):
            try:
                note = finalizer()
            except BaseException:  # noqa: BLE001 - the process ends anyway
                note = None
            if note:
                notes.append(note)
        code, word = self.exit_of(self.cause)
        try:
            sys.stdout.flush()
        except BaseException:  # noqa: BLE001
            pass
        os.write(2, ("; ".join([word, *notes]) + "\n").encode("utf-8", "replace"))
        os._exit(code)


def flush_stdout() -> None:
    try:
        sys.stdout.flush()
    except (OSError, ValueError):  # the reader is gone, or the disk is full
        silence_stdout()


def silence_stdout() -> None:
    """Point stdout at /dev/null: the reader is gone, and Python's final
    flush must not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # no real file descriptor (tests capture stdout)
        pass


__all__ = [
    "Stops",
    "Terminated",
    "DeadlineExceeded",
    "TimedOut",
    "Haltable",
    "interrupt",
    "timeout_reason",
    "is_stop",
    "flush_stdout",
    "silence_stdout",
    "INTERRUPT_EXIT",
    "SIGTERM_EXIT",
    "TIMEOUT_EXIT",
    "START",
    "COMMAND",
    "EXIT",
]
