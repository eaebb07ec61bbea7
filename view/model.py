"""The page's input: the events of a run, as ``htn run --log`` writes them.

A page is driven by nothing but log records (see docs/executor.md, the event log, and
:mod:`htn.executor.tree_events`): the ``header``, the ``tree`` events that
give the task tree and each graft, and every event about an action, which
names its tree node (``node``). The same records come live from a run's
:class:`~htn.executor.log.EventLog` or from a log file, so a finished log is
shown exactly as the run was.

A log written before ``tree`` events existed has no task tree: the view
then shows one node per step number (:func:`page_records` adds that tree as
a record marked ``synthetic``, which no timeline lists).
"""

from __future__ import annotations

import json
import os

from htn.jshop.language.errors import HtnError

OUTCOMES = ("finished", "verified", "failed", "aborted", "retrying", "interrupted")


def read_log(path: str) -> tuple[list[dict], str | None]:
    """The records of the log file ``path`` and a warning (or None).

    Every line must be a JSON object with an ``event``, the first one the
    ``header``; otherwise an input error at that line. A last line cut short
    (a run killed while writing it) is left out, with a warning."""
    if not os.path.isfile(path):
        raise HtnError("no such log file", path)
    try:
        with open(path, encoding="utf-8-sig") as fh:
            lines = fh.read().split("\n")
    except (OSError, UnicodeDecodeError) as exc:
        raise HtnError(f"not a log of htn run --log: {exc}", path) from exc
    records: list[dict] = []
    warning = None
    last = len(lines) - 1
    while last >= 0 and not lines[last].strip():
        last -= 1
    for number, line in enumerate(lines[: last + 1], 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
        except json.JSONDecodeError as exc:
            if number == len(lines) and records:  # no newline after it: cut short
                warning = f"{path}:{number}: the last line is incomplete; left out"
                break
            raise HtnError(f"not a JSON line: {exc.msg}", path, number, exc.colno) from exc
        if not isinstance(rec, dict) or not isinstance(rec.get("event"), str):
            raise HtnError('not an event of htn run --log (no "event")', path, number, 1)
        if not records and rec["event"] != "header":
            raise HtnError(
                "not a log of htn run --log: its first line is no header event", path, number, 1
            )
        records.append(rec)
    if not records:
        raise HtnError("not a log of htn run --log: the file is empty", path)
    return records, warning


def page_records(records: list[dict]) -> list[dict]:
    """The records a page shows: ``records`` as they are when they hold a
    ``tree`` event; else with a flat tree of one node per step number after
    the header, and each event about a step naming that node."""
    if any(r.get("event") == "tree" for r in records):
        return records
    numbers: dict = {}
    for r in records:
        if r.get("step") is not None and r["step"] not in numbers:
            numbers[r["step"]] = (len(numbers) + 1, r.get("action") or f"step {r['step']}")
    nodes = [{"id": 0, "parent": None, "task": "(root)", "label": ""}]
    for step, (number, text) in sorted(numbers.items()):
        nodes.append(
            {"id": number, "parent": 0, "task": text, "label": f"step {step}", "step": step}
        )
    tree = {
        "t": records[0].get("t", 0.0),
        "sim_t": records[0].get("sim_t", 0.0),
        "step": None,
        "action": None,
        "event": "tree",
        "attempt": None,
        "detail": "no task tree in this log: one node per step",
        "nodes": nodes,
        "parent": None,
        "replaces": [],
        "synthetic": True,
    }
    out = [records[0], tree]
    for r in records[1:]:
        if r.get("step") is not None and "node" not in r:
            r = {**r, "node": numbers[r["step"]][0]}
        out.append(r)
    return out


def title_of(header: dict) -> str:
    """What the page's title bar says about a run: plan, robot, faults, seed."""
    plan = os.path.basename(header.get("plan") or "") or "plan"
    parts = [plan, f"robot {header.get('robot') or '?'}"]
    if header.get("faults"):
        parts.append(f"faults {header['faults']}")
    if header.get("seed") is not None:
        parts.append(f"seed {header['seed']}")
    if header.get("replan"):
        parts.append("replan")
    return " · ".join(parts)
