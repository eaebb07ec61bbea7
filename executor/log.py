"""The outcome log: one JSON object per event, written and flushed as it
happens, so an interrupted run still leaves a complete, parseable file.

Its first event (``header``) records what is needed to run the same thing
again (:func:`run_header`; ``htn run --from-log`` reads it back with
:func:`read_header`); its last one is the run's ``summary``.
"""
from __future__ import annotations

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


def run_header(plan_file, plan_sha256, plan_index, domain, problem, functions, robot, seed,
               faults, retries, replan, argv) -> dict:
    """What a log's header records: enough to run the same thing again
    (``argv``: the command line as given, None for a program's call), with
    the plan file's SHA-256 (of the bytes the run read) and the versions it
    ran with."""
    import platform
    from importlib.metadata import PackageNotFoundError, version

    from htn.installation import version as htn_version

    def installed(name):
        try:
            return version(name)
        except PackageNotFoundError:
            return None
    absolute = lambda p: os.path.abspath(p) if p else None  # noqa: E731
    return {"htn": htn_version(), "argv": None if argv is None else list(argv),
            "plan": absolute(plan_file), "plan_sha256": plan_sha256,
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


def check_plan_present(plan_file: Optional[str], log_path: str) -> None:
    """The plan file a header names is there; otherwise an input error at the
    log's first line."""
    if not plan_file:
        raise HtnError("the log records no plan file (its run was of a plan a program "
                       "passed in)", log_path, 1, 1)
    if not os.path.isfile(plan_file):
        raise HtnError(f"the plan file of this run is missing: {plan_file}", log_path, 1, 1)


def check_plan_digest(plan_file: str, recorded: Optional[str], actual: str,
                      log_path: str) -> None:
    """The plan file is unchanged since the logged run (when the header has
    its SHA-256): ``actual`` is the digest of the bytes read now."""
    if recorded and actual != recorded:
        raise HtnError(f"the plan file {plan_file} has changed since this run (SHA-256 "
                       f"{actual[:12]}..., the log says {recorded[:12]}...)", log_path, 1, 1)
