"""Running a command as a process: how it stops (Ctrl-C, SIGTERM, a
deadline, a closed pipe) and how it ends.

One :class:`Stops` object per command holds everything about stopping; the
command owns it and passes it down (the use cases of :mod:`htn.api` take
``stops=``; the user functions run under it). Nothing here is installed by
importing it: :func:`command` installs a command's signal handlers for as
long as it runs, :func:`begin_process` and :func:`end_process` are the first
and last acts of htn's own entry point (:mod:`htn.cli.start`), and a library
that embeds :mod:`htn.api` calls none of them unless it wants to.

* ``stops.py``: the :class:`Stops` of a command, and the stops themselves;
* ``handlers.py``: the signal handlers, the ``--timeout`` deadline;
* ``watchdog.py``: the thread that acts on a stop the program ignores.

This room imports only the standard library and htn's error type.
"""

from .handlers import begin_process, command, deadline, end_process
from .stops import (
    INTERRUPT_EXIT,
    SIGTERM_EXIT,
    TIMEOUT_EXIT,
    DeadlineExceeded,
    Stops,
    Terminated,
    TimedOut,
    silence_stdout,
)

__all__ = [
    "Stops",
    "Terminated",
    "DeadlineExceeded",
    "TimedOut",
    "command",
    "deadline",
    "begin_process",
    "end_process",
    "silence_stdout",
    "INTERRUPT_EXIT",
    "SIGTERM_EXIT",
    "TIMEOUT_EXIT",
]
