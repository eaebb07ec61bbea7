"""Files the use cases and the command line write: every output path is
checked before any work starts, and a file is replaced only by a complete new
result (:class:`AtomicFile`), so that nothing already written is lost or left
half-written.

An output is refused when it is one of the command's inputs (the same file,
also through a symbolic or hard link: the device and inode are compared),
another output of the same command, the command's standard output or error,
or not a regular file (a device, a FIFO, a socket: ``-o /dev/null`` must not
replace ``/dev/null``); ``-`` is refused too (no output option here means
standard output). A symbolic link is written through: its target is
replaced, the link kept. An I/O error while writing (a full disk, a failing
device, a read-only file system) is a :class:`WriteError` naming the path;
the earlier file stays as it was and no temporary is left.
"""

from __future__ import annotations

import atexit
import os
import re
import stat
import threading
from collections.abc import Iterable
from contextlib import contextmanager

from htn.jshop.language.errors import HtnError, WriteError

TEMP_PREFIX = ".htn-"
_pending: set = set()  # temporary files of this process not yet committed


# ---------------------------------------------------------------- output paths
# Every output a command writes is checked before any work starts, with one
# message style: "PATH: OPTION: what is wrong" (OPTION left out where the
# caller does not name it).


def _refused(path: str, option: str | None, message: str):
    return HtnError(f"{option}: {message}" if option else message, path)


def _identity(path) -> tuple | None:
    """(device, inode) of the file at ``path`` (links followed), or None."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_dev, st.st_ino


def _stream_identities() -> dict:
    out = {}
    for fd, name in ((1, "standard output"), (2, "standard error")):
        try:
            st = os.fstat(fd)
        except OSError:
            continue
        if stat.S_ISREG(st.st_mode):  # a terminal or a pipe is no file to clash with
            out[(st.st_dev, st.st_ino)] = name
    return out


KINDS = (
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISSOCK, "a socket"),
)


def check_target(
    path: str, option: str | None, inputs: Iterable = (), others: Iterable = ()
) -> str:
    """The file ``path`` stands for (a symbolic link's target), refused if it
    is ``-``, not a regular file, one of ``inputs`` (paths), one of
    ``others`` (``(path, option)`` of the command's other outputs) or the
    command's standard output or error."""
    if path == "-":
        raise _refused(
            path, option, "'-' is not standard output here: name a file (./- for one called '-')"
        )
    try:
        target = os.path.realpath(path)
        st = os.stat(target) if os.path.lexists(target) else None
    except OSError as exc:
        raise _refused(path, option, f"cannot write: {exc.strerror or exc}") from None
    if st is not None:
        for test, kind in KINDS:
            if test(st.st_mode):
                raise _refused(
                    path, option, f"is {kind}, not a file: htn writes only regular files"
                )
    me = (st.st_dev, st.st_ino) if st is not None else None
    for other, other_option in others:
        if os.path.realpath(other) == target or (me and _identity(other) == me):
            raise _refused(
                path, option, f"is also where {other_option} writes: give each output its own file"
            )
    if me is None:
        return target
    for given in inputs:
        if given is not None and _identity(given) == me:
            same = "" if os.path.realpath(given) == target else f" ({given})"
            raise _refused(
                path,
                option,
                f"is an input of this command{same}: htn does not write over its inputs",
            )
    stream = _stream_identities().get(me)
    if stream:
        raise _refused(path, option, f"is this command's {stream}")
    return target


def check_output_file(
    path: str, option: str | None = None, inputs: Iterable = (), others: Iterable = ()
) -> str:
    """Can ``path`` be written as a new file? It is not a folder, its folder
    exists and takes new files, a file already there may be replaced, and it
    is no input nor other output (:func:`check_target`). Returns the folder
    of the file it stands for (a symbolic link's target)."""
    target = check_target(path, option, inputs, others)
    folder = os.path.dirname(target)
    if os.path.isdir(target):
        raise _refused(path, option, "is a folder, not a file")
    if not os.path.isdir(folder):
        raise _refused(path, option, f"no such folder {folder}")
    if os.path.exists(target) and not os.access(target, os.W_OK):
        raise _refused(path, option, "cannot write: permission denied")
    _probe(folder, path, option)
    return folder


def check_output_folder(
    path: str, option: str, inputs: Iterable = (), others: Iterable = ()
) -> None:
    """Can ``path`` be a folder to write files in? It is one, or it can be
    made under the nearest folder that exists. Nothing is made here (see
    :func:`make_output_folder`), so a later check that fails leaves no trace."""
    if path == "-":
        raise _refused(path, option, "'-' is not a folder: name one")
    if os.path.exists(path) and not os.path.isdir(path):
        raise _refused(path, option, "is a file, not a folder")
    target = os.path.realpath(path)
    for other, other_option in others:
        if os.path.realpath(other) == target:
            raise _refused(path, option, f"is also where {other_option} writes")
    existing = target
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
        import tempfile  # only where a file is written: htn plan to stdout does not

        tempfile.TemporaryFile(dir=folder, prefix=TEMP_PREFIX).close()
    except OSError as exc:
        raise _refused(path, option, f"cannot write in {folder}: {exc.strerror or exc}") from None


class AtomicFile:
    """A file that replaces ``path`` only when :meth:`commit` is called.

    Content goes to ``.htn-<pid>-*`` beside the file (beside a symbolic
    link's target: the link stays); :meth:`discard` (or the end of the
    process, or the next htn writing to that folder after a SIGKILL) removes
    it, so readers never see a half-written file and an earlier file is
    replaced only by a complete new one. Opening checks the path
    (:func:`check_output_file`, with the command's ``inputs`` and ``others``
    outputs; ``option`` names the option in messages), so a bad path fails
    before any work. An I/O error while writing or committing is a
    :class:`WriteError`, with the temporary removed and any earlier file
    as it was; the file is then failed (:attr:`failed`) and commits nothing.
    """

    def __init__(
        self,
        path: str,
        option: str | None = None,
        inputs: Iterable = (),
        others: Iterable = (),
        binary: bool = False,
    ):
        self.path, self.option = path, option
        directory = check_output_file(path, option, inputs, others)
        self.target = os.path.realpath(path)
        remove_stale_temporaries(directory)
        try:
            import tempfile

            fd, self.tmp = tempfile.mkstemp(prefix=f"{TEMP_PREFIX}{os.getpid()}-", dir=directory)
        except OSError as exc:
            raise _refused(
                path, option, f"cannot write in {directory}: {exc.strerror or exc}"
            ) from None
        _pending.add(self.tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(self.tmp, 0o666 & ~umask)  # mkstemp makes 0600; a plan file is ordinary
        self.fh = os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8")
        self.failed: WriteError | None = None
        self.done = False
        self.lock = threading.Lock()  # the watchdog may commit from its thread

    def _failing(self, exc: OSError) -> WriteError:
        self.discard()
        what = f"{self.option}: " if self.option else ""
        self.failed = WriteError(f"{what}cannot write: {exc.strerror or exc}", self.path)
        return self.failed

    def write(self, data) -> None:
        if self.failed is not None:
            raise self.failed
        try:
            self.fh.write(data)
        except OSError as exc:
            raise self._failing(exc) from None

    def flush(self) -> None:
        if self.failed is not None:
            raise self.failed
        try:
            self.fh.flush()
        except OSError as exc:
            raise self._failing(exc) from None

    def commit(self) -> None:
        """Replace the file with what was written (its data on the disk first)."""
        with self.lock:
            if self.done:
                return
            if self.failed is not None:
                raise self.failed
            try:
                self.fh.flush()
                os.fsync(self.fh.fileno())
                self.fh.close()
                os.replace(self.tmp, self.target)
            except OSError as exc:
                raise self._failing(exc) from None
            self.done = True
            _pending.discard(self.tmp)

    def discard(self) -> None:
        """Forget what was written; the file stays as it was."""
        self.done = True
        try:
            self.fh.close()
        except OSError:  # what was buffered cannot be written either: it is dropped
            pass
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
    except OSError:  # someone else's process
        return True
    return True


@contextmanager
def atomic_write(
    path: str,
    option: str | None = None,
    inputs: Iterable = (),
    others: Iterable = (),
    binary: bool = False,
):
    """An :class:`AtomicFile` that replaces ``path`` when the block ends
    normally; an exception or an interrupt leaves any earlier file untouched."""
    out = AtomicFile(path, option, inputs, others, binary)
    try:
        yield out
    except BaseException:
        out.discard()
        raise
    out.commit()
