"""``htn``: plan with a JSHOP2 domain, execute plans, evaluate.

This module only parses arguments, calls the library and prints. Errors in the
user's input are :class:`htn.jshop.errors.HtnError`; they are caught once, in
:func:`main`, and printed as ``file:line:col: message`` with exit code 2.
"""
from __future__ import annotations

import os
import sys

import click

from htn.jshop.errors import HtnError

from .output import fail

CONTEXT = dict(help_option_names=["-h", "--help"], max_content_width=100)


@click.group(context_settings=CONTEXT)
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


def _register():
    from .evaluate_cmd import evaluate
    from .examples_cmd import examples
    from .plan_cmd import plan
    from .run_cmd import run
    from .stats_cmd import stats
    from .transform_cmd import transform
    from .validate_cmd import validate
    for command in (plan, run, validate, stats, transform, evaluate, examples):
        cli.add_command(command)


_register()


def main(argv=None) -> None:
    """Console entry point: run the click group, turning input errors into exit 2."""
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 20000))
    try:
        code = cli.main(args=argv, prog_name="htn", standalone_mode=False)
    except HtnError as exc:
        fail(exc)
        sys.exit(2)
    except click.exceptions.Abort:
        click.echo("interrupted", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        exc.show()
        sys.exit(exc.exit_code)
    except KeyboardInterrupt:
        click.echo("interrupted", err=True)
        sys.exit(130)
    except BrokenPipeError:
        # stdout closed early (e.g. piped into head): not an error of ours
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(0)
    sys.exit(code or 0)


if __name__ == "__main__":  # pragma: no cover
    main()
