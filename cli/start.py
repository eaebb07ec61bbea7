"""The ``htn`` entry point: Ctrl-C and SIGTERM while the command line is still
being imported end the process quietly (exit 130, 143), without a traceback;
once imported, each command handles them (``htn run`` halts its robot)."""
import signal

from .signals import interrupt, interrupt_exit


def _before_main(signum, frame):
    # raising here could be swallowed by an import lock's callback: leave at once
    interrupt_exit(interrupt(signum), now=True)


def main(argv=None):
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _before_main)
    from .main import main as cli_main
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    cli_main(argv)
