"""The summary of a run: how it ended, and what it did on the way (the
``summary`` event, the last of the run's log, and the line ``htn run`` prints)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass
class RunSummary:
    result: str  # verified | failed | aborted | interrupted | preempted
    steps: int  # steps of the plan (as repaired), executed or not
    verified: int
    retries: int
    replans: int
    sim_time: float
    failed_step: str | None = None  # the action that ended the run
    failed_at: int | None = None  # its 1-based step
    executed: int = 0  # steps started (each once, however many attempts)
    advice: str | None = None  # what might have saved it (retries used up)
    reason: str | None = None  # why it was halted (interrupted, preempted)

    def as_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        if d["reason"] is None:  # only a halted run's summary says why
            del d["reason"]
        return d

    def line(self) -> str:
        """``aborted: 3 of 8 steps verified, ...; aborted at step 4: (!grasp ...)``,
        and the advice, if any."""
        line = (
            f"{self.result}: {self.verified} of {self.steps} steps verified, "
            f"{self.retries} retries, {self.replans} replans, "
            f"{self.sim_time:.1f} s simulated"
        )
        if self.failed_step:
            line += f"; {self.result} at step {self.failed_at}: {self.failed_step}"
        if self.advice:
            line += f"; {self.advice}"
        return line
