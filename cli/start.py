"""The ``htn`` entry point (and ``python -m htn``).

Its first act installs handlers that end the process quietly on Ctrl-C or
SIGTERM (exit 130, 143, no traceback) while the command line is being
imported; they use only ``os`` and ``signal``, which the interpreter has
loaded already. Then :mod:`htn.cli.signals` takes over (see there: each
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


def main(argv=None):
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _early)
    from . import signals
    signals.begin_process()
    code = 0
    try:
        from .main import main as cli_main
        cli_main(argv)
    except SystemExit as exc:
        code = exc.code
    except KeyboardInterrupt as exc:    # between the command's end and its exit phase
        signals.interrupt_exit(exc, now=True)
    signals.end_process(code)
