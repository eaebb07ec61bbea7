"""Goals recorded in a rosbag2 bag (``htn ros record``), read as the records
of a log for ``htn view``.

``htn ros node`` publishes every executor event on ``/<node>/events``
(``htn_interfaces/msg/Event``), and each message's ``record`` is the event
as one JSON object, exactly the line ``htn run --log`` writes. A goal's
events begin with its ``header`` (the run's settings: what the page's title
shows) and its ``tree``, and end with its ``summary``; so the events of a
bag are the logs of the goals run while it recorded, one after the other,
and nothing else is needed to show one. :func:`read_bag` splits them at
each ``header`` and returns one goal's records (the last, unless told).

A bag is a rosbag2 folder (``metadata.yaml`` beside its storage file) or one
storage file (``.db3``, sqlite3; ``.mcap``). A folder with a ``.db3`` but no
``metadata.yaml`` is a recording that did not end in order (killed, or
still going on): ``rosbags`` writes ``metadata.yaml`` last, and the recorder
commits the database every fraction of a second, so the ``.db3`` is read
instead, with a warning.

Reading needs ``rosbags`` (pure Python, in the ``ros`` extra; no ROS),
imported here only when a bag is read. Messages are decoded with the
message definition the bag holds, or htn's own ``Event.msg`` for a bag
without one. Anything wrong with a bag is an :class:`HtnError` naming it.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from importlib.util import find_spec
from pathlib import Path

from htn.jshop.language.errors import HtnError

EVENT_TYPE = "htn_interfaces/msg/Event"
SUFFIXES = (".db3", ".mcap")
EVENT_MSG = (
    Path(__file__).resolve().parent.parent
    / "ros"
    / "interfaces"
    / "htn_interfaces"
    / "msg"
    / "Event.msg"
)
"""htn's definition of the message, for a bag that holds none."""


@dataclass
class BagGoal:
    """One goal of a bag: its records (as a log's), and what to tell."""

    records: list
    goal: int  # 1-based
    goals: int  # in the bag
    warning: str | None = None

    @property
    def note(self) -> str | None:
        if self.goals < 2:
            return None
        return f"goal {self.goal} of {self.goals}; --goal N shows another"


def is_bag(path) -> bool:
    """Is ``path`` a rosbag2 bag (a folder, a ``.db3`` or ``.mcap`` file)
    rather than a log? Only looks at names: a log's reading stays as fast."""
    p = Path(path)
    if p.is_dir():
        return True  # a log is a file: a folder can only be a bag (or be refused as one)
    return p.suffix.lower() in SUFFIXES


def read_bag(path, goal: int | None = None) -> BagGoal:
    """The records of goal ``goal`` (1-based; None: the last) of the bag at
    ``path``, checked as a log's are: every record a JSON object with an
    ``event``, the goal's first the ``header``."""
    path = str(path)
    events, warnings = _events(path)
    goals: list[list] = []
    before = 0
    for rec in events:
        if rec["event"] == "header":
            goals.append([rec])
        elif goals:
            goals[-1].append(rec)
        else:
            before += 1
    if before:
        warnings.append(
            f"{_events_word(before)} before the first goal's header (the recording "
            "began during a goal) left out"
        )
    if not goals:
        raise HtnError(
            f"no goal's header among the bag's {_events_word(len(events))}: it began "
            "recording during a goal; record before sending one",
            path,
        )
    if goal is not None and not 1 <= goal <= len(goals):
        raise HtnError(
            f"--goal {goal}: the bag holds {_goals(len(goals))} (--goal 1 to {len(goals)})", path
        )
    k = len(goals) if goal is None else goal
    warning = f"{path}: " + "; ".join(warnings) if warnings else None
    return BagGoal(goals[k - 1], k, len(goals), warning)


def _goals(n: int) -> str:
    return "1 goal" if n == 1 else f"{n} goals"


def _events_word(n: int) -> str:
    return "1 event" if n == 1 else f"{n} events"


def _events(path: str) -> tuple[list[dict], list[str]]:
    """Every event record of the bag, in the order recorded, and warnings."""
    if find_spec("rosbags") is None:
        raise HtnError(
            "reading a rosbag2 bag needs rosbags: pip install 'htn[ros]' (or pip install rosbags)",
            path,
        )
    if not os.path.exists(path):
        raise HtnError("no such bag or log file", path)
    source, warnings = _storage(path)
    from rosbags.rosbag2 import Reader

    try:
        with Reader(source) as reader:
            conns = [c for c in reader.connections if c.msgtype == EVENT_TYPE]
            if not conns:
                topics = ", ".join(sorted(f"{c.topic} ({c.msgtype})" for c in reader.connections))
                raise HtnError(
                    f"the bag holds no htn events (no topic of type {EVENT_TYPE}; its "
                    f"topics: {topics or 'none'})",
                    path,
                )
            names = sorted({c.topic for c in conns})
            if len(names) > 1:
                raise HtnError(
                    f"the bag holds the events of several nodes ({', '.join(names)}): "
                    "htn view shows one node's (record one with htn ros record "
                    "--node NAME)",
                    path,
                )
            decode = _decoder(conns[0], path)
            events = [
                _record(decode, data, n, names[0], path)
                for n, (_, _, data) in enumerate(reader.messages(connections=conns), 1)
            ]
    except HtnError:
        raise
    except Exception as exc:  # noqa: BLE001 - rosbags, sqlite, MCAP, YAML: any is a bad bag
        raise HtnError(f"not a readable rosbag2 bag: {_short(exc)}", path) from None
    if not events:
        raise HtnError(f"the bag holds no events on {names[0]} (nothing was recorded)", path)
    return events, warnings


def _storage(path: str) -> tuple[Path, list[str]]:
    """What rosbags opens: the bag itself, or the ``.db3`` of a folder whose
    recording did not end in order."""
    p = Path(path)
    if not p.is_dir() or (p / "metadata.yaml").is_file():
        return p, []
    stores = sorted(p.glob("*.db3"))
    if len(stores) != 1:
        raise HtnError(
            "not a rosbag2 bag: the folder has no metadata.yaml"
            + ("" if not stores else f" and {len(stores)} .db3 files"),
            path,
        )
    return stores[0], [
        f"no metadata.yaml (the recording did not end in order, or is "
        f"still going on): read {stores[0].name} as far as it was written"
    ]


def _decoder(conn, path: str):
    """``data -> message`` for the connection's type, from the bag's own
    message definition (else htn's ``Event.msg``)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    text = getattr(conn.msgdef, "data", "") if conn.msgdef is not None else ""
    if not text or text.startswith("=" * 80):  # none, or IDL: htn's own definition
        try:
            text = EVENT_MSG.read_text(encoding="utf-8")
        except OSError:
            raise HtnError(
                f"the bag holds no definition of {EVENT_TYPE} and {EVENT_MSG} is missing", path
            ) from None
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(text, EVENT_TYPE))
    return lambda data: store.deserialize_cdr(data, EVENT_TYPE)


def _record(decode, data, n: int, topic: str, path: str) -> dict:
    """The event record of message ``n`` (1-based) of ``topic``."""
    where = f"{topic} message {n}"
    try:
        text = decode(data).record
    except Exception as exc:  # noqa: BLE001 - a message cut short or of another layout
        raise HtnError(f"{where}: not an {EVENT_TYPE}: {_short(exc)}", path) from None
    try:
        rec = json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise HtnError(f"{where}: its record is not JSON: {_short(exc)}", path) from None
    if not isinstance(rec, dict) or not isinstance(rec.get("event"), str):
        raise HtnError(f'{where}: its record is no event of htn run --log (no "event")', path)
    return rec


def _short(exc: BaseException) -> str:
    text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    return text if len(text) <= 200 else text[:197] + "..."
