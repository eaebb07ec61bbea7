"""Ending a node's process in bounded time. rclpy's executor threads are not
daemons, so the interpreter's exit waits for them; one stalled in the
middleware (seen once in a CI run: a node that had stopped serving, still
alive 30 s after Ctrl-C) would keep a stopped node's process alive for ever.
Nothing here imports rclpy."""

from __future__ import annotations

import os
import sys
import threading

GRACE = 10.0  # seconds from the start of a node's shutdown to its forced end


def end_within(what: str, seconds: float = GRACE) -> threading.Timer:
    """From now on, end the process after ``seconds`` if it has not ended by
    itself, saying so on stderr (the exit code is 0: the node's work was
    done; only the middleware's threads had not stopped)."""

    def end() -> None:
        sys.stderr.write(
            f"{what}: rclpy's threads did not stop within {seconds:g} s of the "
            "shutdown; the process ends\n"
        )
        sys.stderr.flush()
        sys.stdout.flush()
        os._exit(0)

    timer = threading.Timer(seconds, end)
    timer.daemon = True
    timer.start()
    return timer


def spin(executor, period: float = 0.2) -> None:
    """``executor.spin()`` that looks at the context again every ``period``
    seconds: a shutdown (Ctrl-C, SIGTERM) wakes a waiting executor through a
    guard condition, and a wake-up missed there left a node's main thread
    waiting for ever, before the shutdown's own deadline (:func:`end_within`)
    had started (seen once in CI: ``htn ros node`` still alive 30 s after
    SIGINT)."""
    context = executor.context
    while context.ok():
        executor.spin_once(timeout_sec=period)
