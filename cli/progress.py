"""A spinner with the name of the phase that is running, for work that is
silent otherwise (planning and transforming, reading a large HDDL instance,
building a simulated world): on stderr, only when stderr is a terminal, and
only once the phase has lasted ``DELAY`` seconds, so that quick commands and
piped output stay exactly as they were.

The spinner is rich's ``Status`` (a ``Live`` display with its own refresh
thread); it is started from a timer thread and always stopped (and the timer
joined) when the phase ends, also by an exception or Ctrl-C, before anything
else is printed.
"""

from __future__ import annotations

import sys
import threading
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.status import Status

DELAY = 1.0  # seconds a phase runs before its spinner shows


def stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


class Phase:
    """``with Phase("planning") as p: ... p.update("trying rule tray")``:
    a spinner on stderr while the block runs (see the module's docstring);
    on a pipe or a file it does nothing at all."""

    def __init__(self, text: str, delay: float = DELAY):
        self.text = text
        self.delay = delay
        self._lock = threading.Lock()
        self._status: Status | None = None
        self._timer: threading.Timer | None = None
        self._ended = False

    def __enter__(self) -> Phase:
        if stderr_is_terminal():
            self._timer = threading.Timer(self.delay, self._show)
            self._timer.daemon = True
            self._timer.start()
        return self

    def _show(self) -> None:
        with self._lock:
            if self._ended:
                return
            from rich.console import Console

            self._status = Console(stderr=True).status(self.text, spinner="dots")
            self._status.start()

    def update(self, text: str) -> None:
        """The phase that runs now (the spinner's text)."""
        with self._lock:
            self.text = text
            if self._status is not None:
                self._status.update(text)

    def __exit__(self, *exc) -> None:
        self.end()

    def end(self) -> None:
        """Stop the spinner (it leaves no line behind); idempotent."""
        if self._timer is not None:
            self._timer.cancel()
            if self._timer is not threading.current_thread():
                self._timer.join()
        with self._lock:
            self._ended = True
            if self._status is not None:
                self._status.stop()
                self._status = None
