"""The view of a run going on (``htn run PLAN --view``).

:class:`RunView` starts the server before the robot moves, then, once the
run's log and task dispatcher exist, takes every event the log emits (a log
listener: one list append and at most one wake-up of the server's loop) and,
for a robot with a camera (:meth:`htn.robot.interface.Robot.camera_frame`:
the PyBullet robots), renders camera frames in the robot's own thread
between two ticks, and only while a page is connected. PyBullet is never
touched from the server's thread.

The camera's rate is bounded twice: at most ``FRAME_RATE`` frames a second,
and at most ``CAMERA_SHARE`` of the robot thread's time (a frame that took
``d`` seconds to render is followed by none for ``d / CAMERA_SHARE``); a
last frame is rendered when the run ends.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from .hub import Hub
from .model import title_of
from .server import ViewServer

if TYPE_CHECKING:
    from htn.robot.interface import Robot

FRAME_RATE = 4.0  # camera frames a second, at most
CAMERA_SHARE = 0.25  # of the robot thread's time, at most
FRAME_SIZE = (320, 240)


class RunView:
    """The browser view of one run, served on ``host``:``port``."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0):
        self.hub = Hub("live")
        self.server = ViewServer(self.hub, host, port)
        self.robot: Robot | None = None  # a robot with a camera, once attached
        self._next_frame = 0.0
        self.camera_seconds = 0.0  # spent rendering, in the robot's thread

    @property
    def url(self) -> str:
        return self.server.url

    def start(self) -> RunView:
        self.server.start()
        return self

    def attach(self, log, dispatcher, robot) -> None:
        """Show the run of ``dispatcher`` on ``robot`` whose events go to ``log``:
        the events so far, then each as it is emitted."""
        from htn.robot.interface import Robot

        hub = self.hub
        header = next((r for r in log.events if r["event"] == "header"), None)
        camera = type(robot).camera_frame is not Robot.camera_frame
        hub.begin(
            list(log.events),
            title_of(header) if header else "",
            camera,
            time.time() - (time.perf_counter() - log.start),
        )
        log.listeners.append(hub.publish)
        if camera:
            self.robot = robot
            dispatcher.tick_listeners.append(self._tick)
            log.listeners.append(self._last_frame)

    def _tick(self) -> None:
        """Between two ticks: a camera frame, if one is due and a page watches."""
        if not self.hub.pages:
            return
        now = time.perf_counter()
        if now >= self._next_frame:
            spent = self._render()
            self._next_frame = now + max(1.0 / FRAME_RATE, spent / CAMERA_SHARE)

    def _last_frame(self, record: dict) -> None:
        if record["event"] == "summary" and self.robot is not None:
            self._render()

    def _render(self) -> float:
        assert self.robot is not None  # rendered only for an attached camera
        start = time.perf_counter()
        frame = self.robot.camera_frame(*FRAME_SIZE)
        spent = time.perf_counter() - start
        self.camera_seconds += spent
        if frame:
            self.hub.set_frame(frame, self.robot.sim_time)
        return spent

    def wait_for_page(self, timeout: float | None = None) -> bool:
        """Block until a page has connected and shown the run so far (Ctrl-C
        still interrupts)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self.hub.watching.wait(0.1):
            if deadline is not None and time.monotonic() > deadline:
                return False
        return True

    def close(self) -> None:
        self.server.close()


class GoalsView:
    """The browser view of a robot node's goals (``htn ros node --view``):
    each goal's run as ``htn run --view`` shows one, fed by its events; a page
    open when the next goal begins loads that goal's run."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0):
        self.server = ViewServer(Hub("live"), host, port)

    @property
    def url(self) -> str:
        return self.server.url

    def start(self) -> GoalsView:
        self.server.start()
        return self

    def event(self, record: dict) -> None:
        """One event of the goal being run (its ``header`` begins a new run)."""
        if record.get("event") == "header":
            hub = Hub("live")
            hub.begin(
                [record], title_of(record), False, time.time() - float(record.get("t") or 0.0)
            )
            self.server.switch(hub)
        else:
            self.server.hub.publish(record)

    def close(self) -> None:
        self.server.close()
