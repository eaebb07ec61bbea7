"""Shared output helpers for the command line: messages on stderr, files
that are replaced only by a complete new result."""
from __future__ import annotations

import atexit
import os
import re
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


TEMP_PREFIX = ".htn-"
_pending: set = set()       # temporary files of this process not yet committed


class AtomicFile:
    """A file that replaces ``path`` only when :meth:`commit` is called.

    Content goes to ``.htn-<pid>-*`` beside ``path``; :meth:`discard` (or the
    end of the process, or the next htn writing to that folder after a
    SIGKILL) removes it, so readers never see a half-written file and an
    earlier file is replaced only by a complete new one. Opening checks that
    the file can be written at all, so a bad path fails before any work.
    """

    def __init__(self, path: str):
        from htn.jshop.errors import HtnError
        self.path = path
        directory = os.path.dirname(os.path.abspath(path))
        if os.path.isdir(path):
            raise HtnError("is a directory, not a file", path)
        if not os.path.isdir(directory):
            raise HtnError("directory does not exist", path)
        if os.path.exists(path) and not os.access(path, os.W_OK):
            raise HtnError("cannot write: permission denied", path)
        remove_stale_temporaries(directory)
        try:
            fd, self.tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{os.getpid()}-", dir=directory)
        except OSError as exc:
            raise HtnError(f"cannot write here: {exc.strerror}", path) from None
        _pending.add(self.tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(self.tmp, 0o666 & ~umask)      # mkstemp makes 0600; a plan file is ordinary
        self.fh = os.fdopen(fd, "w", encoding="utf-8")

    def write(self, text: str) -> None:
        self.fh.write(text)

    def flush(self) -> None:
        self.fh.flush()

    def commit(self) -> None:
        """Replace ``path`` with what was written."""
        self.fh.close()
        os.replace(self.tmp, self.path)
        _pending.discard(self.tmp)

    def discard(self) -> None:
        """Forget what was written; ``path`` stays as it was."""
        self.fh.close()
        _remove(self.tmp)


def _remove(tmp: str) -> None:
    try:
        os.unlink(tmp)
    except FileNotFoundError:
        pass
    _pending.discard(tmp)


@atexit.register
def _remove_pending() -> None:
    for tmp in list(_pending):
        _remove(tmp)


def remove_stale_temporaries(directory: str) -> None:
    """Remove ``.htn-<pid>-*`` files in ``directory`` whose process is gone
    (killed with SIGKILL, which no handler sees)."""
    try:
        names = os.listdir(directory)
    except OSError:
        return
    for name in names:
        m = _TEMP_NAME.match(name)
        if m and not _alive(int(m.group(1))):
            try:
                os.unlink(os.path.join(directory, name))
            except OSError:
                pass


_TEMP_NAME = re.compile(re.escape(TEMP_PREFIX) + r"(\d+)-")


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:             # someone else's process
        return True
    return True


@contextmanager
def atomic_write(path: str):
    """An :class:`AtomicFile` that replaces ``path`` when the block ends
    normally; an exception or an interrupt leaves any earlier file untouched."""
    out = AtomicFile(path)
    try:
        yield out
    except BaseException:
        out.discard()
        raise
    out.commit()


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
    try:
        return sys.stdout.isatty()
    except (AttributeError, ValueError):
        return False
