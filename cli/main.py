"""``htn``: plan with a JSHOP2 domain, execute plans, evaluate.

This module runs a command and ends it: the click group (:mod:`.group`)
parses the arguments, or, for a plain ``htn plan DOMAIN PROBLEM`` that needs
none of click's work (:mod:`.fast`), the plan command runs without importing
click, whose import costs more than planning a small problem. Errors in the
user's input are :class:`htn.jshop.language.errors.HtnError`; they are caught once, in
:func:`main`, and printed as ``file:line:col: message`` with exit code 2.
Ctrl-C exits with 130, SIGTERM with 143 (both after the command's own clean-up,
see :mod:`htn.process`), and a reader that closes the pipe early (``htn
plan ... | head -1``) ends the command quietly with 0.
"""

from __future__ import annotations

import errno
import sys
from collections.abc import Callable

from htn.jshop.language.errors import HtnError
from htn.process import DeadlineExceeded, Stops, command, silence_stdout

from .output import fail

# errors writing to a stream (standard output): a full disk, a device that
# fails, a read-only file system, a descriptor that user code closed
STREAM_ERRORS = {errno.ENOSPC, errno.EIO, errno.EROFS, errno.EDQUOT, errno.EFBIG, errno.EBADF}


def main(argv=None, stops: Stops | None = None) -> None:
    """Run a command, turning input errors into exit 2. ``stops``: the
    process's own (:mod:`htn.cli.start`); else the command gets its own, and
    its signal handlers last as long as it runs."""
    from .fast import plain_plan

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 20000))
    args = sys.argv[1:] if argv is None else list(argv)
    plain = plain_plan(args)
    with command(stops) as stops:
        if plain is not None:
            from .plan_run import run_plan

            code = _ended(stops, lambda: run_plan(stops, **plain))
        else:
            code = _ended(stops, lambda: _click(args, stops))
    sys.exit(code or 0)


def _click(args: list[str], stops: Stops) -> int | None:
    """The click group's run; its own errors (a usage error, an interrupt
    outside a command) ended as click ends them."""
    import click

    from .group import cli

    try:
        return cli.main(args=args, prog_name="htn", standalone_mode=False, obj=stops)
    except click.exceptions.Abort as exc:  # click's form of an interrupt outside a command
        stops.interrupt_exit(exc.__context__)
    except click.ClickException as exc:
        exc.show()
        raise _Done(exc.exit_code) from None
    return None


class _Done(Exception):
    """A command that ended with its message shown: its exit code."""

    def __init__(self, code: int):
        super().__init__(code)
        self.code = code


def _ended(stops: Stops, run: Callable[[], int | None]) -> int | None:
    """The exit code of ``run()``: 2 for an input error (printed as one
    line), a signal's code, 0 for a closed pipe."""
    interrupt_exit = stops.interrupt_exit
    code = None
    try:
        code = run()
        sys.stdout.flush()
    except _Done as done:
        code = done.code
    except HtnError as exc:
        fail(exc)
        code = 2
    except (KeyboardInterrupt, DeadlineExceeded) as exc:
        interrupt_exit(exc)
    except RuntimeError as exc:
        # Python 3.11 wraps what __set_name__ raises: a Ctrl-C while a
        # class is made (in an import) comes as its cause
        if not isinstance(exc.__cause__, (KeyboardInterrupt, DeadlineExceeded)):
            raise
        interrupt_exit(exc.__cause__)
    except BrokenPipeError:
        silence_stdout()
        code = 0
    except OSError as exc:
        if exc.filename is not None or exc.errno not in STREAM_ERRORS:
            raise
        # every file htn writes reports its own errors: this is a stream's
        silence_stdout()
        fail(HtnError(f"cannot write: {exc.strerror or exc}", "standard output"))
        code = 2
    if stops.received is not None and not stops.reported:
        interrupt_exit(stops.received)  # a signal the command did not report
    return code


if __name__ == "__main__":  # pragma: no cover
    main()
