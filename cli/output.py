"""Shared printing helpers for the command line (rich on stderr for messages)."""
from __future__ import annotations

import os
import sys
import tempfile
from contextlib import contextmanager

import click


def fail(exc) -> None:
    """Print an input error as one ``file:line:col: message`` line (+ source)."""
    click.echo(f"{exc}", err=True)
    src = exc.source_line() if hasattr(exc, "source_line") else None
    if src:
        click.echo(src, err=True)


def warn(message: str) -> None:
    click.echo(str(message), err=True)


@contextmanager
def atomic_write(path: str):
    """Write a file so that readers never see it half-written.

    Content goes to a temporary file beside ``path`` and replaces it only when
    the block ends, also when it ends by Ctrl-C or a timeout; an exception
    other than an interrupt leaves any earlier file untouched.
    """
    directory = os.path.dirname(os.path.abspath(path)) or "."
    if not os.path.isdir(directory):
        from htn.jshop.errors import HtnError
        raise HtnError("directory does not exist", path)
    fd, tmp = tempfile.mkstemp(prefix=".htn-", dir=directory)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)      # mkstemp makes 0600; a plan file is ordinary
    fh = os.fdopen(fd, "w", encoding="utf-8")
    try:
        yield fh
    except KeyboardInterrupt:
        fh.close()
        os.replace(tmp, path)
        raise
    except BaseException:
        fh.close()
        os.unlink(tmp)
        raise
    fh.close()
    os.replace(tmp, path)


@contextmanager
def deferred_interrupt():
    """Hold back Ctrl-C while a unit of output is written, so that streams and
    files only ever contain whole plans; the interrupt arrives right after."""
    import signal
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def stdout_is_terminal() -> bool:
    try:
        return sys.stdout.isatty()
    except (AttributeError, ValueError):
        return False
