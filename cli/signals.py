"""How a command ends when it is told to: Ctrl-C, SIGTERM, a deadline, a closed pipe.

Every moment of the process is covered, from the entry point's first line
(:mod:`htn.cli.start`) to the exit:

* while the command line is imported, and once the command has ended (while
  the interpreter shuts down), a signal ends the process at once:
  ``interrupted`` (Ctrl-C) or ``terminated`` (SIGTERM), exit code 130 or 143;
* while a command runs (:func:`command`), SIGINT raises ``KeyboardInterrupt``
  and SIGTERM :class:`Terminated` (a kind of it), so every clean-up after
  Ctrl-C (whole plans kept, temporary files removed, logs ended) is done for
  a ``kill`` too. Only the first signal is raised (a second must not break
  the clean-up); any signal still decides the exit code (130, 143);
* output units (a plan, a JSON line) are written in :func:`held` blocks: a
  stop that comes meanwhile is raised when the block ends (a flag, not a
  signal mask: the kernel gives a signal to any thread, a mask holds one);
* ``htn run`` :func:`watch`\\ es its task dispatcher: a signal during a tick
  halts it when the tick ends (the robot holds its pose, the log is ended);
* ``--timeout`` is a wall-clock :func:`deadline`: SIGALRM raises
  :class:`DeadlineExceeded` wherever the program is, also inside a user
  function (during ``htn run``: :class:`TimedOut`, which halts the run).

Stops raised here are marked (:func:`htn.jshop.language.errors.raised_stop`)
so that the wrappers of user code let them pass, and see user code swallow
one; the :mod:`watchdog <htn.cli.watchdog>` raises a dropped one again and
ends user code that keeps swallowing them. This module imports only the
standard library and that marker: the entry point installs it first.
"""
from __future__ import annotations

import os
import signal
import sys
import time
from contextlib import contextmanager

from htn.jshop.language.errors import is_stop, raised_stop

from .watchdog import GRACE, Watchdog, backstop_after, leave_now

INTERRUPT_EXIT = 128 + signal.SIGINT
SIGTERM_EXIT = 128 + signal.SIGTERM
TIMEOUT_EXIT = 1
MAX_TIMER = 1e8          # seconds (three years): a longer --timeout is no limit


class Terminated(KeyboardInterrupt):
    """The process received SIGTERM: stop like Ctrl-C, exit code 143."""

    def __init__(self, reason: str = "stopped by SIGTERM"):
        super().__init__(reason)


class DeadlineExceeded(BaseException):
    """``--timeout`` ran out while the program was busy (e.g. in user code)."""


class TimedOut(KeyboardInterrupt):
    """``--timeout`` ran out during ``htn run``: the run stops like after
    Ctrl-C (the log ends ``interrupted``, with this reason), exit code 1."""


START, COMMAND, EXIT = "start", "command", "exit"


class _State:
    """The process's signal state (one process runs one command at a time)."""

    def __init__(self):
        self.phase = COMMAND        # START/EXIT only when htn.cli.start runs the process
        self.process = False        # htn.cli.start owns the process (not a library caller)
        self.reset()

    def reset(self) -> None:
        self.received = None        # the first SIGINT / SIGTERM (an interrupt)
        self.raised = None          # the stop raised into the program
        self.swallowed = False      # ... and dropped where Python cannot let it out
        self.quiet = False          # record signals only: the command ends in order
        self.holding = 0
        self.pending = None         # came during a held() block
        self.dispatcher = None      # halted during its ticks
        self.timeout = None         # the --timeout in force (seconds)
        self.reported = False       # "interrupted" was printed
        self.started = None         # time.perf_counter() when the command began
        self.watchdog = None
        self.finalizers: list = []  # for the watchdog: () -> note or None


STATE = _State()


def interrupt(signum: int) -> KeyboardInterrupt:
    """The interrupt a signal stands for: :class:`Terminated` for SIGTERM,
    else ``KeyboardInterrupt`` (Ctrl-C)."""
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def _on_signal(signum, frame):
    st = STATE
    exc = interrupt(signum)
    if st.received is None:
        st.received = exc
    if st.phase != COMMAND:
        interrupt_exit(st.received, now=True)
    _deliver(exc)


AGAIN = 0.5     # seconds: the deadline is raised again until the command stops


def _on_alarm(signum, frame):
    st = STATE
    # again until the deadline's block ends: Python drops an exception raised
    # in a finalizer, and even a library caller's command must stop
    if st.dispatcher is None:       # htn run ends by halting its dispatcher, once
        signal.setitimer(signal.ITIMER_REAL, AGAIN)
        if isinstance(st.raised, DeadlineExceeded) and not st.swallowed:
            st.swallowed = True         # raised before and the command goes on: again
    _deliver(TimedOut(timeout_reason(st.timeout)) if st.dispatcher is not None
             else DeadlineExceeded())


def timeout_reason(seconds) -> str:
    return f"--timeout {seconds:g} s ran out" if seconds is not None else "--timeout ran out"


def _deliver(exc: BaseException) -> None:
    """Raise ``exc`` into the program now, later (held, halted) or not at all."""
    st = STATE
    if st.holding:
        if st.pending is None or isinstance(st.pending, DeadlineExceeded):
            st.pending = exc            # an interrupt outranks the deadline
        return
    if st.quiet or (st.raised is not None and not st.swallowed):
        return                          # the command is stopping already
    st.swallowed = False
    st.raised = exc
    if st.watchdog is None and st.process:
        # only in htn's own process: a library caller's (or a test's) process
        # is not ours to interrupt from another thread, nor to end
        st.watchdog = Watchdog(_signal_of, _emergency_exit).begin()
    d = st.dispatcher
    if d is not None and d.in_tick:
        d.halt(str(exc))
        return
    raise raised_stop(exc)


def _signal_of() -> int | None:
    """The signal to raise a swallowed stop again with (None: none swallowed)."""
    st = STATE
    if not st.swallowed or st.raised is None:
        return None
    if isinstance(st.raised, (DeadlineExceeded, TimedOut)):
        return signal.SIGALRM
    return signal.SIGTERM if isinstance(st.raised, Terminated) else signal.SIGINT


def _unraisable(args) -> None:
    # a stop raised in a finalizer or a weakref callback is dropped by Python
    # (with a traceback on stderr): remember it, the watchdog raises it again
    if is_stop(args.exc_value):
        STATE.swallowed = True
        return
    sys.__unraisablehook__(args)


# ------------------------------------------------------------------ phases

def begin_process() -> None:
    """The entry point's first act: from now on a signal ends the process
    at once, until a :func:`command` takes over (and again after it)."""
    STATE.process = True
    STATE.phase = START
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _on_signal)


@contextmanager
def command():
    """While the block runs, signals stop the command (see the module's
    docstring); the caller's handlers come back after it (a library or a
    test may run several commands in one process)."""
    st = STATE
    st.reset()
    st.started = time.perf_counter()
    st.phase = COMMAND
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, ())    # put back after (user code)
    try:
        old = {sig: signal.signal(sig, _on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:          # not the main thread: leave signals alone
        old = {}
    hook, sys.unraisablehook = sys.unraisablehook, _unraisable
    try:
        yield st
    finally:
        if st.process:
            st.phase = EXIT     # first: a signal from now on ends the process at once
        if st.watchdog is not None:
            st.watchdog.cancel()
        sys.unraisablehook = hook
        for sig, handler in old.items():
            signal.signal(sig, handler)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def end_process(code) -> None:
    """The entry point's last act: exit with ``code``, or 130/143 if a
    signal came that the command did not report."""
    st = STATE
    st.phase = EXIT
    if st.received is not None and not st.reported:
        interrupt_exit(st.received)
    flush_stdout()
    if st.process:      # the shutdown puts the default handlers back: a signal
        leave_now(code)     # then kills the process (-2, seen after htn run --sim)
    sys.exit(code)


def flush_stdout() -> None:
    try:
        sys.stdout.flush()
    except (OSError, ValueError):       # the reader is gone, or the disk is full
        silence_stdout()


def interrupt_exit(exc: BaseException | None, note: str = "", now: bool = False):
    """End the process after the stop ``exc``: "terminated" (SIGTERM),
    "timed out" (the deadline) or "interrupted" (anything else), then
    ``; note`` if given, on stderr; exit code 143, 1 or 130. ``now``: leave
    at once (``os._exit``) instead of through the interpreter's shutdown,
    for a handler that runs while modules are imported or the interpreter
    shuts down, and after PyBullet, whose shutdown after a Ctrl-C was seen
    (rarely) to end the process by SIGINT instead of the exit code."""
    st = STATE
    if st.received is not None and isinstance(exc, (TimedOut, DeadlineExceeded)):
        exc = st.received       # a signal came too: it decides
    st.reported = True
    code, word = exit_of(exc)
    flush_stdout()
    try:
        sys.stderr.write(word + (f"; {note}" if note else "") + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
    if now and st.process:      # a library caller's process is not ours to end
        os._exit(code)
    sys.exit(code)


def exit_of(exc) -> tuple[int, str]:
    """The exit code and the word a stop ends a command with."""
    if isinstance(exc, Terminated):
        return SIGTERM_EXIT, "terminated"
    if isinstance(exc, (TimedOut, DeadlineExceeded)):
        seconds = STATE.timeout
        return TIMEOUT_EXIT, "timed out" + (f" after {seconds:g} s" if seconds else "")
    return INTERRUPT_EXIT, "interrupted"


def silence_stdout() -> None:
    """Point stdout at /dev/null: the reader is gone, and Python's final
    flush must not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):   # no real file descriptor (tests capture stdout)
        pass


# ------------------------------------------------------------------ during a command

def raise_again() -> None:
    """Raise the stop once more if Python dropped it (it was raised in a
    finalizer: the search drops generators all the time) and the command
    goes on. A command calls this where it may stop (after each plan)."""
    st = STATE
    if st.swallowed and st.raised is not None:
        st.swallowed = False
        raise raised_stop(st.raised)


def settle() -> None:
    """From now on signals are only recorded (they set the exit code): the
    command ends in order (``htn run`` after its summary)."""
    STATE.dispatcher = None
    STATE.quiet = True


def listen_again() -> None:
    """Signals raise again (``htn run --view`` keeps its page up until
    Ctrl-C); one that came while they were only recorded raises now."""
    st = STATE
    st.quiet = False
    st.raised, st.swallowed = None, False
    if st.received is not None:
        exc, st.received = st.received, None
        raise raised_stop(exc)


def consume() -> None:
    """The signal that came ends the command normally (``htn view``: Ctrl-C
    is how a server stops), not with 130/143."""
    STATE.received = None


def watch(dispatcher) -> None:
    """From now on a signal (or the deadline) during a tick of
    ``dispatcher`` halts it. One that came before raises now: the tree must
    not start after a Ctrl-C that was swallowed."""
    st = STATE
    if st.raised is not None:
        raise raised_stop(st.raised)
    st.dispatcher = dispatcher


def on_emergency(finalizer) -> None:
    """``finalizer()`` (returning a note or None) keeps what is whole if the
    watchdog has to end the process (see :mod:`htn.cli.watchdog`)."""
    STATE.finalizers.append(finalizer)


def _emergency_exit(stuck: str) -> None:
    st = STATE
    if not st.process:          # a library caller's process is not ours to end
        return
    waited = time.monotonic()
    while st.holding and time.monotonic() - waited < 1.0:    # a unit being written
        time.sleep(0.01)
    notes = [stuck]
    for finalizer in reversed(st.finalizers):
        try:
            note = finalizer()
        except BaseException:       # noqa: BLE001 - the process ends anyway
            note = None
        if note:
            notes.append(note)
    exc = st.received or st.raised
    code, word = exit_of(exc)
    try:
        sys.stdout.flush()
    except BaseException:           # noqa: BLE001
        pass
    os.write(2, ("; ".join([word, *notes]) + "\n").encode("utf-8", "replace"))
    os._exit(code)


@contextmanager
def held():
    """Hold back Ctrl-C, SIGTERM and the deadline while a unit of output is
    written; one that came meanwhile is raised right after."""
    st = STATE
    st.holding += 1
    try:
        yield
    finally:
        st.holding -= 1
        if not st.holding and st.pending is not None:
            exc, st.pending = st.pending, None
            _deliver(exc)


# ------------------------------------------------------------------ the deadline

@contextmanager
def deadline(seconds: float | None, started: float | None = None):
    """Raise :class:`DeadlineExceeded` (during ``htn run``: halt it with
    :class:`TimedOut`) once ``seconds`` have passed since ``started`` (a
    ``time.perf_counter()`` value; default: now). None (or more than
    :data:`MAX_TIMER`): no limit. If code that holds the interpreter (a C
    extension) keeps the handler from running at all, the process ends
    with exit code 1 :data:`GRACE` + 2 seconds after the deadline."""
    if seconds is None or seconds > MAX_TIMER:
        yield
        return
    st = STATE
    remaining = seconds - (time.perf_counter() - started if started is not None else 0.0)
    try:
        old = signal.signal(signal.SIGALRM, _on_alarm)
    except ValueError:          # not the main thread: the planner's own check must do
        yield
        return
    outer, st.timeout = st.timeout, seconds
    signal.setitimer(signal.ITIMER_REAL, max(remaining, 1e-3))
    # a library caller's process is not ours to end
    backstop = st.process and backstop_after(max(remaining, 0.0) + GRACE + 2.0)
    try:
        yield
    finally:
        while True:
            try:
                signal.setitimer(signal.ITIMER_REAL, 0)
                break
            except DeadlineExceeded:    # raised again as it was being cancelled
                continue
        if backstop:
            import faulthandler
            faulthandler.cancel_dump_traceback_later()
        signal.signal(signal.SIGALRM, old)
        st.timeout = outer if outer is not None else st.timeout
