"""The outcome log: one JSON object per event, written and flushed as it
happens, so an interrupted run still leaves a complete, parseable file.

Its first event (``header``) records what is needed to run the same thing
again (:mod:`htn.executor.log_header`); its last one is the run's ``summary``.
Each event is one line written with one system call (:class:`LineFile`), so
the file only ever holds whole lines: a full disk (or a failing device) cuts
it back to its last whole line, and the summary is still written when the
disk allows.
"""

from __future__ import annotations

import json
import os
import threading
import time
from collections.abc import Callable
from typing import Any

from htn.jshop.language.errors import WriteError

from .log_header import read_header as read_header  # the log's header, re-exported
from .log_header import run_header as run_header


class LineFile:
    """A file written line by line, each line whole or not at all.

    An I/O error cuts the file back to its last whole line and raises a
    :class:`~htn.jshop.language.errors.WriteError` naming the path (and
    ``option``); after it, only a ``last`` line (a summary) is tried once
    more, and silently dropped if it does not fit either."""

    def __init__(self, path: str, option: str | None = None):
        self.path, self.option = path, option
        self.failed: WriteError | None = None
        self.size = 0  # bytes of whole lines written
        self.lock = threading.Lock()  # the watchdog may end the file from its thread
        try:
            self.fd: int | None = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
        except OSError as exc:
            raise self._error(exc) from None

    def _error(self, exc: OSError) -> WriteError:
        what = f"{self.option}: " if self.option else ""
        return WriteError(f"{what}cannot write: {exc.strerror or exc}", self.path)

    def write_line(self, text: str, last: bool = False) -> bool:
        """Append ``text`` and a newline; False if it was dropped (the file
        failed earlier). ``last``: the final line, tried even then."""
        data = (text + "\n").encode("utf-8")
        with self.lock:
            if self.fd is None or (self.failed is not None and not last):
                return False
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(self.fd, view) :]
            except OSError as exc:
                self._cut()
                if self.failed is None:
                    self.failed = self._error(exc)
                    raise self.failed from None
                return False
            self.size += len(data)
            return True

    def _cut(self) -> None:
        """Back to the last whole line (what follows it is half a line)."""
        assert self.fd is not None  # write_line's, under the lock: the file is open
        try:
            os.ftruncate(self.fd, self.size)
            os.lseek(self.fd, self.size, os.SEEK_SET)
        except OSError:
            pass

    def close(self) -> None:
        with self.lock:
            if self.fd is not None:
                try:
                    os.close(self.fd)
                except OSError:
                    pass
                self.fd = None


class EventLog:
    """Writes ``{"t", "sim_t", "step", "action", "event", "attempt", "detail"}`` lines.

    ``t`` is wall-clock seconds since the log was opened, ``sim_t`` seconds of
    simulated (robot) time; ``step`` is 1-based. Listeners (e.g. the live
    view) get every event too. :attr:`ended` tells whether the ``summary``
    is in; a file that cannot be written raises
    :class:`~htn.jshop.language.errors.WriteError` at the first event that
    does not fit (the run then ends with its summary, if the disk allows).
    """

    def __init__(
        self,
        path: str | None = None,
        clock: Callable[[], float] | None = None,
        option: str | None = "--log",
    ):
        self._file: LineFile | None = LineFile(path, option) if path else None
        self.path = path
        self.clock = clock or (lambda: 0.0)
        self.start = time.perf_counter()
        self.listeners: list[Callable[[dict[str, Any]], object]] = []
        self.events: list[dict[str, Any]] = []
        self.ended = False

    @property
    def failed(self) -> WriteError | None:
        return self._file.failed if self._file is not None else None

    def emit(
        self,
        step: int | None,
        action: str | None,
        event: str,
        attempt: int | None = None,
        detail: str = "",
        sim_t: float | None = None,
        **extra: Any,
    ) -> dict[str, Any]:
        record: dict[str, Any] = {
            "t": round(time.perf_counter() - self.start, 4),
            "sim_t": round(self.clock() if sim_t is None else sim_t, 4),
            "step": step,
            "action": action,
            "event": event,
            "attempt": attempt,
            "detail": detail,
            **extra,
        }
        last = event == "summary"
        if self.ended:
            return record  # a run ends once (the watchdog may have ended it)
        self.ended = last
        self.events.append(record)
        if self._file is not None:
            self._file.write_line(json.dumps(record), last=last)
        for listener in self.listeners:
            listener(record)
        return record

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


# the one line htn run prints (and htn ros send) for each thing that happened
SHOWN = (
    "verified",
    "failed",
    "aborted",
    "retrying",
    "replanned",
    "replan_failed",
    "interrupted",
    "fault",
)


def event_line(rec: dict[str, Any]) -> str | None:
    """``' 3 verified    (!goto robby dock kitchen)  [try 1, t=2.0s] DETAIL'``
    for an event of the run's log worth a line, else None (starts, ticks,
    feedback: the live tree shows those)."""
    if rec["event"] not in SHOWN:
        return None
    step = "" if rec["step"] is None else f"{rec['step']:>2} "
    what = rec["action"] or ""
    if rec["event"] == "fault":
        return f"{step}{'fault':<11} {rec['kind']}: {rec['detail']}  [t={rec['sim_t']:.2f}s]"
    if rec["event"] == "replanned":
        what = rec["path"]
    return (
        f"{step}{rec['event']:<11} {what}  "
        f"[try {rec['attempt'] or '-'}, t={rec['sim_t']:.1f}s] {rec['detail']}"
    )
