"""The ``htn`` entry point: Ctrl-C and SIGTERM while the command line is still
being imported end the process quietly (exit 130, 143), without a traceback;
once imported, each command handles them (``htn run`` halts its robot)."""
import os
import signal
import sys


def _before_main(signum, frame):
    sys.stderr.write("interrupted\n" if signum == signal.SIGINT else "terminated\n")
    sys.stderr.flush()
    os._exit(130 if signum == signal.SIGINT else 143)


def main(argv=None):
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _before_main)
    from htn.cli.main import main as cli_main
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    cli_main(argv)
