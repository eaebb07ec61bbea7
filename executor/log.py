"""The outcome log: one JSON object per event, written and flushed as it
happens, so an interrupted run still leaves a complete, parseable file."""
from __future__ import annotations

import json
import time
from typing import IO, Optional


class EventLog:
    """Writes ``{"t", "sim_t", "step", "action", "event", "attempt", "detail"}`` lines.

    ``t`` is wall-clock seconds since the log was opened, ``sim_t`` seconds of
    simulated (robot) time; ``step`` is 1-based. Listeners (e.g. the live
    view) get every event too.
    """

    def __init__(self, path: Optional[str] = None, clock=None):
        self._fh: Optional[IO[str]] = open(path, "w", encoding="utf-8") if path else None
        self.path = path
        self.clock = clock or (lambda: 0.0)
        self.start = time.perf_counter()
        self.listeners: list = []
        self.events: list[dict] = []

    def emit(self, step: Optional[int], action: Optional[str], event: str,
             attempt: Optional[int] = None, detail: str = "", sim_t: Optional[float] = None,
             **extra) -> dict:
        record = {"t": round(time.perf_counter() - self.start, 4),
                  "sim_t": round(self.clock() if sim_t is None else sim_t, 4),
                  "step": step, "action": action, "event": event, "attempt": attempt,
                  "detail": detail, **extra}
        self.events.append(record)
        if self._fh is not None:
            self._fh.write(json.dumps(record) + "\n")
            self._fh.flush()
        for listener in self.listeners:
            listener(record)
        return record

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None
