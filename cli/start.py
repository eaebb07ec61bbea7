"""The ``htn`` entry point (and ``python -m htn``).

Its first act installs handlers that end the process quietly on Ctrl-C or
SIGTERM (exit 130, 143, no traceback) while the command line is being
imported; they use only ``os`` and ``signal``, which the interpreter has
loaded already. Then :mod:`htn.process` takes over (see there: each
command handles signals, and after the command a signal ends the process
at once), and the exit code of the command is the process's, unless a
signal came that it did not report.

What comes before this module's first line (the interpreter's own start-up,
a few milliseconds unloaded) is outside any Python program's reach: a signal
then ends the process as the signal's default does.
"""

import os
import signal


def _early(signum, frame):
    # nothing of htn is imported yet: say it and leave, without the interpreter's shutdown
    os.write(2, b"terminated\n" if signum == signal.SIGTERM else b"interrupted\n")
    os._exit(128 + signum)


def _whole_writes() -> None:
    # -u or PYTHONUNBUFFERED=1 leave stdout and stderr without a buffered
    # layer: a write that a signal interrupts part way (the deadline's timer,
    # into a full pipe) then drops what the kernel did not take, and a plan's
    # JSON line is cut in two. A BufferedWriter writes the rest; line
    # buffering keeps the output as prompt. (The old streams stay alive as
    # sys.__stdout__ and sys.__stderr__, so the file descriptors stay open.)
    import io
    import sys

    for name in ("stdout", "stderr"):
        stream = getattr(sys, name)
        raw = getattr(stream, "buffer", None)
        if isinstance(raw, io.RawIOBase):
            setattr(
                sys,
                name,
                io.TextIOWrapper(
                    io.BufferedWriter(raw),
                    encoding=stream.encoding,
                    errors=stream.errors,
                    line_buffering=True,
                ),
            )


def main(argv=None):
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _early)
    _whole_writes()
    from htn.process import Stops, begin_process, end_process

    stops = Stops(owned=True)  # the process is htn's: a stop may end it
    begin_process(stops)
    code = 0
    try:
        from .main import main as cli_main

        cli_main(argv, stops)
    except SystemExit as exc:
        code = exc.code
    except KeyboardInterrupt as exc:  # between the command's end and its exit phase
        stops.interrupt_exit(exc, now=True)
    end_process(stops, code)
