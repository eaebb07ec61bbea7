"""Files the use cases and the command line write: every output path is
checked before any work starts, and a file is replaced only by a complete new
result (:class:`AtomicFile`), so that nothing already written is lost or left
half-written."""
from __future__ import annotations

import atexit
import os
import re
import tempfile
from contextlib import contextmanager

from htn.jshop.language.errors import HtnError

TEMP_PREFIX = ".htn-"
_pending: set = set()       # temporary files of this process not yet committed


# ---------------------------------------------------------------- output paths
# Every output a command writes is checked before any work starts, with one
# message style: "PATH: OPTION: what is wrong" (OPTION left out where the
# caller does not name it).

def _refused(path: str, option: str | None, message: str):
    return HtnError(f"{option}: {message}" if option else message, path)


def check_output_file(path: str, option: str | None = None) -> str:
    """Can ``path`` be written as a new file? It is not a folder, its folder
    exists and takes new files, and a file already there may be replaced.
    Returns the folder."""
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise _refused(path, option, "is a folder, not a file")
    if not os.path.isdir(folder):
        raise _refused(path, option, f"no such folder {folder}")
    if os.path.exists(path) and not os.access(path, os.W_OK):
        raise _refused(path, option, "cannot write: permission denied")
    _probe(folder, path, option)
    return folder


def check_output_folder(path: str, option: str) -> None:
    """Can ``path`` be a folder to write files in? It is one, or it can be
    made under the nearest folder that exists. Nothing is made here (see
    :func:`make_output_folder`), so a later check that fails leaves no trace."""
    if os.path.exists(path) and not os.path.isdir(path):
        raise _refused(path, option, "is a file, not a folder")
    existing = os.path.abspath(path)
    while not os.path.exists(existing):
        existing = os.path.dirname(existing)
    if not os.path.isdir(existing):
        raise _refused(path, option, f"cannot make a folder under {existing}, which is a file")
    _probe(existing, path, option)


def make_output_folder(path: str, option: str) -> None:
    """Make the folder ``path`` (checked with :func:`check_output_folder`)."""
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        raise _refused(path, option, f"cannot make the folder: {exc.strerror or exc}") from None
    _probe(path, path, option)


def _probe(folder: str, path: str, option: str | None) -> None:
    """Can files be created in ``folder``? (Asked by creating one: permission
    bits say nothing to root, read-only file systems say it only then.)"""
    try:
        tempfile.TemporaryFile(dir=folder, prefix=TEMP_PREFIX).close()
    except OSError as exc:
        raise _refused(path, option, f"cannot write in {folder}: {exc.strerror or exc}") from None


class AtomicFile:
    """A file that replaces ``path`` only when :meth:`commit` is called.

    Content goes to ``.htn-<pid>-*`` beside ``path``; :meth:`discard` (or the
    end of the process, or the next htn writing to that folder after a
    SIGKILL) removes it, so readers never see a half-written file and an
    earlier file is replaced only by a complete new one. Opening checks that
    the file can be written at all (:func:`check_output_file`; ``option``
    names the option in its messages), so a bad path fails before any work.
    """

    def __init__(self, path: str, option: str | None = None):
        self.path = path
        directory = check_output_file(path, option)
        remove_stale_temporaries(directory)
        try:
            fd, self.tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{os.getpid()}-", dir=directory)
        except OSError as exc:
            raise _refused(path, option, f"cannot write in {directory}: "
                                         f"{exc.strerror or exc}") from None
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
def atomic_write(path: str, option: str | None = None):
    """An :class:`AtomicFile` that replaces ``path`` when the block ends
    normally; an exception or an interrupt leaves any earlier file untouched."""
    out = AtomicFile(path, option)
    try:
        yield out
    except BaseException:
        out.discard()
        raise
    out.commit()
