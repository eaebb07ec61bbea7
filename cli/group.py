"""The ``htn`` click group: its commands, each imported when it is looked up,
and the command groups of plugins (``htn.commands`` entry points)."""

from __future__ import annotations

import importlib

import click

from htn.process import Stops, silence_stdout

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
