"""Labelled snapshots of a run (``htn run --snapshots DIR``): a PNG per action
attempt, named and captioned by its step, attempt and outcome.

The task dispatcher's event log calls :func:`snapshot_listener`'s function
with each event; at an attempt's outcome (verified, failed, aborted) the
robot's camera saves ``step04_try2_aborted.png`` with a caption
(:class:`~htn.robot.interface.Caption`: step, action, attempt, outcome,
simulated time, the monitor's detail).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from htn.robot.interface import Caption, Robot

OUTCOMES = ("verified", "failed", "aborted")


def snapshot_listener(robot: Robot, folder: str) -> Callable[[dict[str, Any]], None]:
    """An event-log listener that saves a labelled snapshot per attempt outcome."""

    def on_event(rec: dict[str, Any]) -> None:
        if rec["event"] in OUTCOMES and rec["step"] is not None:
            attempt = rec["attempt"] or 1
            name = f"step{rec['step']:02d}_try{attempt}_{rec['event']}.png"
            robot.snapshot(
                os.path.join(folder, name),
                label=Caption(
                    rec["step"],
                    rec["action"] or "",
                    attempt,
                    rec["event"],
                    rec.get("sim_t") or robot.sim_time,
                    rec.get("detail") or "",
                ),
            )

    return on_event
