"""Between the robot's thread and the browsers: the events and the camera.

The robot's thread (the task dispatcher's tick loop, and the log's listeners
it calls) only ever does two cheap things here: :meth:`Hub.publish` appends
an event record to the history and :meth:`Hub.set_frame` replaces the one
latest camera frame; each then asks the server's event loop, at most once
until the loop has looked, to wake the pages' senders. Nothing waits for a
browser, so a slow or closed page never blocks a tick.

The hand-over is a bounded queue of one slot per page: each page's sender
(:meth:`Hub.serve`, in the server's loop) sends what it has not yet sent, in
one batch, then waits for the next wake-up. While a slow page is still
taking a batch, what happens meanwhile is coalesced into its next one:
events are never lost (they are the history, which the run's log holds
anyway, and a page that connects late gets all of it), camera frames are
dropped (only the latest is ever sent).

Messages to a page are JSON texts (``hello``, ``events``, ``frame``) and, after
each ``frame``, the JPEG as a binary message. An ``events`` message says
when it was sent (``sent``, wall-clock seconds), so a page can tell the
server's share of an event's delay from its own.
"""

from __future__ import annotations

import asyncio
import json
import threading
import time

BATCH = 20000  # events per message, at most (a page shows each message at once)


class _Page:
    """One connected page: how far it got."""

    def __init__(self):
        self.sent = 0  # events sent
        self.frame = 0  # number of the last frame sent
        self.wake = asyncio.Event()


class Hub:
    """The events of one run (or log) and its latest camera frame, for every page.

    ``mode`` is ``live`` (a run going on) or ``log`` (a finished log);
    ``wall_start`` the wall-clock time (``time.time()``) of the log's ``t``
    = 0, when known, so a page can tell how late an event reached it."""

    def __init__(
        self,
        mode: str,
        records=(),
        title: str = "",
        camera: bool = False,
        wall_start: float | None = None,
    ):
        self.mode, self.title, self.camera, self.wall_start = mode, title, camera, wall_start
        self.history: list[dict] = list(records)
        self.frame: tuple[int, float, bytes] | None = None  # (number, sim_t, jpeg)
        self.frames = 0
        self.pages = 0  # connected now (read by the robot's thread)
        self.loop: asyncio.AbstractEventLoop | None = None
        self._pages: set = set()
        self._poked = False
        self._closed = False
        self.next_goal = False  # closed because another run begins (a node's goals)
        self._texts: dict = {}
        self.begun = mode != "live"  # a live run's pages wait for begin()
        self.watching = threading.Event()  # set once a page has shown what it got

    # ------------------------------------------------------------ the robot's thread
    def publish(self, record: dict) -> None:
        """A log listener: one more event (never blocks)."""
        self.history.append(record)
        self._poke()

    def set_frame(self, jpeg: bytes, sim_t: float) -> None:
        """The latest camera image (never blocks; an unsent older one is dropped)."""
        self.frames += 1
        self.frame = (self.frames, sim_t, jpeg)
        self._poke()

    def begin(self, records, title: str, camera: bool, wall_start: float) -> None:
        """A live run's log exists: its first records, and what pages are told first."""
        self.history.extend(records)
        self.title, self.camera, self.wall_start = title, camera, wall_start
        self.begun = True
        self._poke(force=True)

    def close(self, next_goal: bool = False) -> None:
        """No more events: the pages' senders end (their pages say the view is
        closed; ``next_goal``: they are told to load the next run instead)."""
        self.next_goal = next_goal
        self._closed = True
        self._poke(force=True)

    def _poke(self, force: bool = False) -> None:
        loop = self.loop
        if loop is None or (self._poked and not force):
            return
        self._poked = True
        try:
            loop.call_soon_threadsafe(self._wake)
        except RuntimeError:  # the loop has stopped: nobody is listening
            pass

    # ------------------------------------------------------------ the server's loop
    def _wake(self) -> None:
        self._poked = False  # first: what comes after this gets a wake-up of its own
        for page in self._pages:
            page.wake.set()

    def hello(self) -> dict:
        return {
            "type": "hello",
            "mode": self.mode,
            "title": self.title,
            "camera": self.camera,
            "wall_start": self.wall_start,
            "events": len(self.history),
        }

    async def serve(self, send_text, send_bytes) -> None:
        """Send one page everything, then each change, until the hub closes
        (or the page goes: the caller cancels this)."""
        page = _Page()
        self._pages.add(page)
        self.pages += 1
        try:
            while not self.begun and not self._closed:  # the robot is still being built
                page.wake.clear()
                await page.wake.wait()
            await send_text(json.dumps(self.hello()))
            while True:
                page.wake.clear()
                await self._send_new(page, send_text, send_bytes)
                if self._closed:
                    if self.next_goal:
                        await send_text('{"type": "next"}')
                    return
                await page.wake.wait()
        finally:
            self._pages.discard(page)
            self.pages -= 1

    def _batch_text(self, start: int, batch: list) -> str:
        """An ``events`` message; a log's (which never changes) is made once for all pages."""
        key = (start, len(batch))
        if self.mode == "log" and key in self._texts:
            return self._texts[key]
        events = json.dumps(batch)
        text = f'{{"type": "events", "from": {start}, "sent": {time.time()}, "events": {events}}}'
        if self.mode == "log":
            self._texts[key] = text
        return text

    def page_said(self, text: str) -> None:
        """A message from a page: ``{"type": "ready"}`` once it has shown what
        it got first (so a run that waits for a page starts now)."""
        try:
            message = json.loads(text)
        except ValueError:
            return
        if isinstance(message, dict) and message.get("type") == "ready":
            self.watching.set()

    async def _send_new(self, page: _Page, send_text, send_bytes) -> None:
        while page.sent < len(self.history):
            start = page.sent
            batch = self.history[start : start + BATCH]
            page.sent = start + len(batch)
            await send_text(self._batch_text(start, batch))
        frame = self.frame
        if frame is not None and frame[0] != page.frame:
            page.frame = frame[0]
            await send_text(
                json.dumps({"type": "frame", "number": frame[0], "sim_t": round(frame[1], 4)})
            )
            await send_bytes(frame[2])
