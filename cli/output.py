"""Shared output helpers for the command line: messages on stderr, rich
consoles that treat a closed pipe like any other write. (Output paths and
files replaced only whole are :mod:`htn.files`, which the use cases share.)"""

from __future__ import annotations

import re
import sys

MESSAGE_LIMIT = 1000  # characters: each quoted term is cut to 200 already


def fail(exc) -> None:
    """Print an input error as one ``file:line:col: message`` line (+ source),
    cut to :data:`MESSAGE_LIMIT` characters (its middle left out) whatever
    it quotes."""
    text = f"{exc}"
    if len(text) > MESSAGE_LIMIT:
        half = MESSAGE_LIMIT // 2
        text = f"{text[:half]} ... {text[-half:]}"
    _echo(text)
    src = exc.source_line() if hasattr(exc, "source_line") else None
    if src:
        _echo(src)


def warn(message: str) -> None:
    _echo(str(message))


_ANSI = re.compile(r"\033\[[;?0-9]*[a-zA-Z]")  # click's pattern of a colour code


def _echo(line: str) -> None:
    """A line on stderr as ``click.echo(line, err=True)`` writes it (colour
    codes left out where stderr is no terminal), without importing click:
    ``htn plan`` runs without it (:mod:`.fast`)."""
    stream = sys.stderr
    if stream is None:
        return
    if not _isatty(stream):
        line = _ANSI.sub("", line)
    stream.write(line + "\n")
    stream.flush()


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def console(**kwargs):
    """A rich ``Console`` for which a closed pipe is a ``BrokenPipeError``,
    like for any other write (rich itself exits with 1), so the command can
    keep what it has and :mod:`htn.cli.main` exit quietly."""
    from rich.console import Console

    class _Console(Console):
        def on_broken_pipe(self) -> None:
            raise BrokenPipeError()

    return _Console(**kwargs)


def stdout_is_terminal() -> bool:
    return _isatty(sys.stdout)
