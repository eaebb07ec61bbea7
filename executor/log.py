"""The outcome log: one JSON object per event, written and flushed as it
happens, so an interrupted run still leaves a complete, parseable file.

Its first event (``header``) records what is needed to run the same thing
again (:func:`run_header`; ``htn run --from-log`` reads it back with
:func:`read_header`); its last one is the run's ``summary``.
"""
from __future__ import annotations

import hashlib
import json
import os
import time
from typing import IO, Optional

from htn.jshop.language.errors import HtnError


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


def run_header(plan_file, plan_index, domain, problem, functions, robot, seed, faults,
               retries, replan, argv: list[str]) -> dict:
    """What a log's header records: enough to run the same thing again
    (``argv``: the command line as given), with the plan file's SHA-256 and
    the versions it ran with."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    import htn

    def installed(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return None
    absolute = lambda p: os.path.abspath(p) if p else None  # noqa: E731
    return {"htn": htn.__version__, "argv": list(argv),
            "plan": absolute(plan_file), "plan_sha256": _sha256(plan_file),
            "plan_index": plan_index, "domain": absolute(domain), "problem": absolute(problem),
            "functions": absolute(functions), "robot": robot, "seed": seed, "faults": faults,
            "retries": dict(sorted(retries.items())), "replan": replan,
            "python": platform.python_version(), "pybullet": installed("pybullet")}


HEADER_KEYS = ("plan", "plan_index", "domain", "problem", "robot", "seed", "faults",
               "retries", "replan")


def read_header(path: str) -> dict:
    """The header event of a log written by ``htn run --log``."""
    if not os.path.isfile(path):
        raise HtnError("no such log file", path)
    try:
        with open(path, encoding="utf-8") as fh:
            first = fh.readline()
        rec = json.loads(first)
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise HtnError(f"not a log of htn run --log: {exc}", path, 1, 1)
    if not isinstance(rec, dict) or rec.get("event") != "header":
        raise HtnError("not a log of htn run --log: its first line is no header event",
                       path, 1, 1)
    missing = [k for k in HEADER_KEYS if k not in rec]
    if missing:
        raise HtnError(f"the header lacks {', '.join(missing)}", path, 1, 1)
    return rec


def check_plan_digest(plan_file: str, digest: Optional[str], log_path: str) -> None:
    """The plan file a header names is there and unchanged (when the header
    has its SHA-256); otherwise an input error at the log's first line."""
    if not os.path.isfile(plan_file):
        raise HtnError(f"the plan file of this run is missing: {plan_file}", log_path, 1, 1)
    now = _sha256(plan_file)
    if digest and now != digest:
        raise HtnError(f"the plan file {plan_file} has changed since this run (SHA-256 "
                       f"{now[:12]}..., the log says {digest[:12]}...)", log_path, 1, 1)


def _sha256(path: str) -> str:
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()
