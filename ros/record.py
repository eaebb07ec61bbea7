"""Recording an htn node's topics into a rosbag2 bag (``htn ros record``).

The recorder subscribes to ``/<node>/events`` (``htn_interfaces/msg/Event``:
every executor event, its ``record`` the line ``htn run --log`` writes, the
goal's ``header`` first) and ``/<node>/facts`` (``htn_interfaces/msg/Facts``:
what other nodes told the world model), and writes each message as it comes
into a new rosbag2 folder with ``rosbags`` (pure Python: no ROS install, no
``ros2 bag``). Reading a bag back is :mod:`htn.view.bag`'s (``htn view``),
which needs no rclpy.

* Storage: sqlite3 (``OUTPUT/OUTPUT.db3``), the format ``rosbags`` writes by
  default and every ``ros2 bag`` since Foxy reads; metadata version 9 (Jazzy).
* Messages are stored as they came over the wire (the subscriptions take
  the serialised CDR, as ``ros2 bag record`` does): nothing is decoded and
  encoded again. Each connection records the type's definition and its
  RIHS01 hash from a ``rosbags`` typestore (Jazzy's, with htn's ``.msg``
  files registered); the hash is the one rclpy announces for the type.
* Timestamps are the receive times (nanoseconds since the epoch), made
  strictly increasing, so the bag's order is the order received.
* Interrupted: the database is committed every :data:`COMMIT_EVERY` seconds
  while messages come, and ``metadata.yaml`` is written when the recording
  ends in order (Ctrl-C, SIGTERM, ``duration``). A recorder that is killed
  leaves the folder without ``metadata.yaml``; its ``.db3`` holds what was
  committed, and ``htn view`` reads it (with a warning).
* An OUTPUT that exists is refused: nothing already written is replaced.

This module imports rclpy; :mod:`htn.ros.record_commands` imports it only
when the command runs.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass, field
from pathlib import Path

from htn.jshop.language.errors import HtnError

from .interfaces import SOURCE, import_interfaces

TOPICS = {"events": "htn_interfaces/msg/Event", "facts": "htn_interfaces/msg/Facts"}
"""The node's topics recorded (``/<node>/<name>``) and their types."""
COMMIT_EVERY = 0.2  # seconds: what a killed recorder can lose, at most
DEPTH = 1000  # messages a subscription keeps while the recorder writes


@dataclass
class Recording:
    """What a recording wrote: ``counts`` of messages per topic."""

    path: str
    counts: dict = field(default_factory=dict)

    @property
    def messages(self) -> int:
        return sum(self.counts.values())

    def line(self) -> str:
        each = ", ".join(f"{n} on {topic}" for topic, n in self.counts.items())
        return f"recorded {self.messages} messages ({each}) in {self.path}"


def check_output(output: str) -> Path:
    """``output`` as a new bag's folder: refused (an input error) if it
    exists, or if the folder it would be made in does not."""
    out = Path(output)
    if out.exists() or out.is_symlink():
        raise HtnError(
            "already exists: htn ros record writes a new bag and replaces nothing "
            "(give another name)",
            output,
        )
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise HtnError(f"no such folder: {parent}", output)
    return out


def typestore():
    """Jazzy's types with htn_interfaces' messages registered (for the
    connections' definitions and hashes)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    found: dict = {}
    for path in sorted((SOURCE / "msg").glob("*.msg")):
        found.update(
            get_types_from_msg(path.read_text(encoding="utf-8"), f"htn_interfaces/msg/{path.stem}")
        )
    store.register(found)
    return store


class BagWriter:
    """A new bag at ``path`` with one connection per recorded topic; each
    :meth:`write` stores one serialised message, committed within
    :data:`COMMIT_EVERY` seconds (:meth:`tick`)."""

    def __init__(self, path: Path, topics: dict[str, str], store):
        from rosbags.rosbag2 import Writer
        from rosbags.rosbag2.errors import WriterError

        self.path = path
        try:
            self.writer = Writer(path, version=getattr(Writer, "VERSION_LATEST", 8))
            self.writer.open()
        except (WriterError, OSError) as exc:
            raise HtnError(f"cannot write the bag: {exc}", str(path)) from None
        self.connections = {
            t: self.writer.add_connection(t, msgtype, typestore=store)
            for t, msgtype in topics.items()
        }
        self.counts = {t: 0 for t in topics}
        self._last = 0
        self._dirty = False
        self._committed = time.monotonic()
        self._commit()

    def write(self, topic: str, data: bytes) -> None:
        stamp = max(time.time_ns(), self._last + 1)  # the order received, whatever the clock
        try:
            self.writer.write(self.connections[topic], stamp, data)
        except Exception as exc:  # noqa: BLE001 - sqlite: a full disk, a removed folder
            raise HtnError(f"cannot write the bag: {exc}", str(self.path)) from None
        self._last = stamp
        self.counts[topic] += 1
        self._dirty = True

    def tick(self) -> None:
        """Commit what was written if the last commit is :data:`COMMIT_EVERY` old."""
        if self._dirty and time.monotonic() - self._committed >= COMMIT_EVERY:
            self._commit()

    def _commit(self) -> None:
        # rosbags commits its sqlite3 database only when the bag is closed
        conn = getattr(self.writer.storage, "conn", None)
        if conn is not None and conn.in_transaction:
            conn.commit()
        self._dirty = False
        self._committed = time.monotonic()

    def close(self) -> None:
        """Commit the rest and write ``metadata.yaml``: the bag is complete."""
        if self.writer.storage is not None:
            try:
                self.writer.close()
            except Exception as exc:  # noqa: BLE001 - as write's
                raise HtnError(f"cannot finish the bag: {exc}", str(self.path)) from None


def record(
    output: str,
    node_name: str = "htn",
    duration: float | None = None,
    *,
    say: Callable[[str], None] = lambda line: None,
    held=nullcontext,
) -> Recording:
    """Record ``/<node_name>/events`` and ``/<node_name>/facts`` into the new
    bag ``output`` until ``duration`` seconds have passed (None: no limit)
    or a ``KeyboardInterrupt`` (Ctrl-C, SIGTERM) comes, which ends the
    recording in order; returns what was recorded. ``say`` gets one-line
    progress messages; ``held()`` is entered around each write (the
    command's :meth:`htn.process.Stops.held`: a stop waits until the message
    is written)."""
    out = check_output(output)
    import rclpy
    from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions

    types = import_interfaces(say)
    store = typestore()
    topics = {f"/{node_name}/{name}": msgtype for name, msgtype in TOPICS.items()}
    classes = {TOPICS["events"]: types.Event, TOPICS["facts"]: types.Facts}
    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)  # htn's own handlers stay
    node = None
    bag = None
    try:
        node = rclpy.create_node(f"htn_record_{os.getpid()}")
        bag = BagWriter(out, topics, store)
        qos = QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=DEPTH, reliability=ReliabilityPolicy.RELIABLE
        )

        def writer(topic):
            def write(data):
                with held():
                    bag.write(topic, data)

            return write

        for topic, msgtype in topics.items():
            node.create_subscription(classes[msgtype], topic, writer(topic), qos, raw=True)
        say(f"recording {', '.join(topics)} into {out} (Ctrl-C stops)")
        _spin(node, bag, next(iter(topics)), node_name, duration, say)
    except KeyboardInterrupt:
        if bag is None:  # before the bag existed: nothing was recorded
            raise
    finally:
        if bag is not None:
            bag.close()
        if node is not None:
            node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()
    return Recording(str(out), dict(bag.counts))


def _spin(node, bag: BagWriter, events: str, node_name: str, duration: float | None, say) -> None:
    """Take messages until ``duration`` is over (or an interrupt); say when
    the node's events topic gets (or loses) its publisher."""
    import rclpy

    end = None if duration is None else time.monotonic() + duration
    publishers = 0
    say(f"waiting for a publisher on {events} (htn ros node --name {node_name})")
    while end is None or time.monotonic() < end:
        rclpy.spin_once(node, timeout_sec=0.05)
        bag.tick()
        n = node.count_publishers(events)
        if n != publishers:
            say(
                f"{events}: {n} publisher{'s' if n != 1 else ''}"
                + ("" if n else " (the node has gone; still recording)")
            )
            publishers = n
