"""``htn examples [DIR]``: the bundled domains and problems; copy them to start from."""
from __future__ import annotations

import re
import shutil
from pathlib import Path

import click

from htn.installation import EXAMPLES
from htn.jshop.language.errors import HtnError

from .output import stdout_is_terminal

FOLDERS = {"domains": ("*.jshop", "*.toml"), "problems": ("*.jshop",)}


def bundled() -> list[Path]:
    """The bundled example files, domains first (retry limits beside them)."""
    out: list[Path] = []
    for folder, patterns in FOLDERS.items():
        for pattern in patterns:
            out.extend(sorted((EXAMPLES / folder).glob(pattern)))
    return out


def summary(path: Path) -> str:
    """The first sentence of a file's leading comment (its description)."""
    words: list[str] = []
    for line in path.read_text(encoding="utf-8").splitlines():
        text = line.strip()
        if not text.startswith(";") and not text.startswith("#"):
            break
        words.append(text.lstrip(";# ").strip())
    text = " ".join(w for w in words if w)
    end = re.search(r"\.\s+(?=[A-Z\"(])", text)    # not "Fig. 7"
    return text[:end.start() + 1] if end else text


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
    files = bundled()
    if not files:
        raise HtnError("no bundled examples found in this installation", str(EXAMPLES))
    if dest is None:
        _list(files, EXAMPLES)
        return
    target = Path(dest)
    pairs = [(f, target / f.parent.name / f.name) for f in files]
    clash = [str(t) for _, t in pairs if t.exists()]
    if clash and not force:
        raise HtnError(f"{len(clash)} file(s) exist already, e.g. {clash[0]} "
                       "(use --force to overwrite)", dest)
    from htn.files import check_target
    for src, dst in pairs:     # no device, FIFO or bundled file itself is written over
        if dst.exists() or dst.is_symlink():
            check_target(str(dst), None, [src])
    for src, dst in pairs:
        try:
            dst.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src, dst)
        except OSError as exc:
            raise HtnError(f"cannot copy {src.name}: {exc.strerror}", str(dst))
    click.echo(f"copied {len(pairs)} files to {target}/domains and {target}/problems")
    click.echo("next:\n  cd " + click.format_filename(str(target))
               + "\n  htn plan domains/domestic.jshop problems/bring_object.jshop -o plan.txt"
               "\n  htn run plan.txt --robot symbolic")


def _list(files: list[Path], root: Path) -> None:
    rows = [(f.parent.name, f.name, summary(f)) for f in files if f.suffix == ".jshop"]
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
