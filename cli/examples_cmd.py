"""``htn examples [DIR]``: the bundled domains and problems; copy them to start from."""

from __future__ import annotations

from pathlib import Path

import click

from htn.api.examples import EXAMPLES, copy_examples, list_examples

from .output import stdout_is_terminal


@click.command("examples")
@click.argument("dest", required=False, type=click.Path(file_okay=False), metavar="[DIR]")
@click.option("--force", is_flag=True, help="Overwrite files that already exist in DIR.")
def examples(dest, force):
    """List the bundled example domains and problems; with DIR, copy them
    into DIR/domains and DIR/problems to start from.

    \b
    Examples:
      htn examples
      htn examples my-robot && cd my-robot
      htn plan domains/domestic.jshop problems/bring_object.jshop -o plan.txt
    """
    if dest is None:
        _list(list_examples(), EXAMPLES)
        return
    target = Path(dest)
    copied = copy_examples(dest, force=force)
    click.echo(f"copied {len(copied)} files to {target}/domains and {target}/problems")
    click.echo(
        "next:\n  cd "
        + click.format_filename(str(target))
        + "\n  htn plan domains/domestic.jshop problems/bring_object.jshop -o plan.txt"
        "\n  htn run plan.txt --robot symbolic"
    )


def _list(rows: list[tuple[str, str, str]], root: Path) -> None:
    if not stdout_is_terminal():
        for folder, name, text in rows:
            click.echo(f"{folder}/{name}\t{text}")
        return
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    t = Table(title=f"bundled examples ({root})", title_justify="left")
    t.add_column("file", style="bold", no_wrap=True)
    t.add_column("what it is")
    for folder, name, text in rows:
        t.add_row(f"{folder}/{name}", escape(text))
    console = Console()
    console.print(t)
    console.print("[dim]copy them to start from: htn examples DIR[/dim]")
