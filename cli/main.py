"""``htn``: plan with a JSHOP2 domain, execute plans, evaluate.

This module only parses arguments, calls the library and prints. Errors in the
user's input are :class:`htn.jshop.language.errors.HtnError`; they are caught once, in
:func:`main`, and printed as ``file:line:col: message`` with exit code 2.
Ctrl-C exits with 130, SIGTERM with 143 (both after the command's own clean-up,
see :mod:`htn.process`), and a reader that closes the pipe early (``htn
plan ... | head -1``) ends the command quietly with 0.
"""

from __future__ import annotations

import errno
import importlib
import sys

import click

from htn.jshop.language.errors import HtnError
from htn.process import DeadlineExceeded, Stops, command, silence_stdout

from .output import fail

# errors writing to a stream (standard output): a full disk, a device that
# fails, a read-only file system, a descriptor that user code closed
STREAM_ERRORS = {errno.ENOSPC, errno.EIO, errno.EROFS, errno.EDQUOT, errno.EFBIG, errno.EBADF}

CONTEXT = dict(help_option_names=["-h", "--help"], max_content_width=100)


class HtnGroup(click.Group):
    """The command group; it ends a command on a closed pipe or an interrupt
    before click does (click would exit 1 on a broken pipe). Its commands
    are imported when they are looked up (click's lazily loaded
    subcommands): ``htn plan`` does not import ``htn run``'s executor or
    ``htn evaluate``'s statistics."""

    def list_commands(self, ctx):
        return sorted({*super().list_commands(ctx), *_COMMANDS, *_plugins()})

    def get_command(self, ctx, name):
        # an unknown name loads them all: click suggests the close ones it has
        for wanted in [name] if name in _COMMANDS else list(_COMMANDS):
            if wanted not in self.commands:
                module = importlib.import_module(f"htn.cli.{_COMMANDS[wanted]}")
                self.add_command(getattr(module, wanted), wanted)
        plugins = {} if name in _COMMANDS else _plugins()
        if name not in self.commands and name in plugins:
            self.add_command(plugins[name].load(), name)
        return super().get_command(ctx, name)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except BrokenPipeError:
            silence_stdout()
            ctx.exit(0)
        except SystemExit as exc:
            # rich's Console exits 1 on a broken pipe (after silencing stdout)
            if exc.code == 1 and isinstance(exc.__context__, BrokenPipeError):
                ctx.exit(0)
            raise
        except KeyboardInterrupt as exc:
            ctx.ensure_object(Stops).interrupt_exit(exc)


@click.group(cls=HtnGroup, context_settings=CONTEXT)
@click.version_option(package_name="htn", prog_name="htn")
def cli():
    """Plan with a JSHOP2-compatible HTN planner, run plans with monitoring,
    and optimise them by transforming their task trees.

    \b
    Quick start (the bundled examples: htn examples DIR copies them):
      htn examples demo && cd demo
      htn plan domains/domestic.jshop problems/bring_object.jshop -o plan.txt
      htn run plan.txt --robot symbolic      # or --sim, with the 'sim' extra
    """


# command name -> its module in htn.cli (the command is the module's attribute of that name)
_COMMANDS = {
    "plan": "plan_cmd",
    "run": "run_cmd",
    "validate": "validate_cmd",
    "stats": "stats_cmd",
    "transform": "transform_cmd",
    "evaluate": "evaluate_cmd",
    "examples": "examples_cmd",
    "view": "view_cmd",
}


def _plugins() -> dict:
    """Command groups other parts of htn (``htn ros``, the ros extra) or other
    packages add through the entry-point group ``htn.commands``: the command
    line imports none of them until it is asked for one."""
    from importlib.metadata import entry_points

    return {ep.name: ep for ep in entry_points(group="htn.commands")}


def main(argv=None, stops: Stops | None = None) -> None:
    """Run the click group, turning input errors into exit 2. ``stops``:
    the process's own (:mod:`htn.cli.start`); else the command gets its
    own, and its signal handlers last as long as it runs."""
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 20000))
    with command(stops) as stops:
        interrupt_exit = stops.interrupt_exit
        try:
            code = cli.main(args=argv, prog_name="htn", standalone_mode=False, obj=stops)
            sys.stdout.flush()
        except HtnError as exc:
            fail(exc)
            code = 2
        except click.exceptions.Abort as exc:  # click's form of an interrupt outside a command
            interrupt_exit(exc.__context__)
        except click.ClickException as exc:
            exc.show()
            code = exc.exit_code
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
    sys.exit(code or 0)


if __name__ == "__main__":  # pragma: no cover
    main()
