"""The one line ``htn run`` prints for each thing that happened (an action's
outcome with its monitor's detail, a fault, a retry, a repair): the lines a
pipe gets, and the scrolling log above the live tree on a terminal."""
from __future__ import annotations

from typing import Optional

SHOWN = ("verified", "failed", "aborted", "retrying", "replanned", "replan_failed",
         "interrupted", "fault")


def event_line(rec: dict) -> Optional[str]:
    """``' 3 verified    (!goto robby dock kitchen)  [try 1, t=2.0s] DETAIL'``
    for an event of the run's log worth a line, else None (starts, ticks,
    feedback: the live tree shows those)."""
    if rec["event"] not in SHOWN:
        return None
    step = "" if rec["step"] is None else f"{rec['step']:>2} "
    what = rec["action"] or ""
    if rec["event"] == "fault":
        return f"{step}{'fault':<11} {rec['kind']}: {rec['detail']}  [t={rec['sim_t']:.2f}s]"
    if rec["event"] == "replanned":
        what = rec["path"]
    return (f"{step}{rec['event']:<11} {what}  "
            f"[try {rec['attempt'] or '-'}, t={rec['sim_t']:.1f}s] {rec['detail']}")
