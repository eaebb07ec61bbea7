"""Where a study's runs execute when ``--workers N`` asks for a local cluster.

Starting N worker processes costs seconds (:func:`.cluster.start_seconds`),
which a small study never wins back: 200 projected runs take about as long
as starting two workers. So the first batch runs in this process, and its
time, per run, projects the rest of the study; the workers are started only
when the rest would end sooner on them, start-up included:

    rest in this process:  t = (seconds per run) x (runs left)
    rest on the workers:   start + t / min(N, cores) / EFFICIENCY

and by a margin (:data:`MARGIN`), since a projection from one batch is
rough. Otherwise every run stays here, and one line says why. A run depends
only on its seed, so the results are the same either way. Times are CPU
seconds of this process, which is what a run costs on an idle machine.
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Callable, Optional

EFFICIENCY = 0.9        # of each worker, against this process (sending tasks, results)
MARGIN = 1.15           # the workers must be this much faster to be started


@dataclass
class Projection:
    """The rest of a study, projected from the batches run so far."""
    runs: int                   # runs of the study
    left: int                   # runs not yet done
    per_run: float              # seconds per run (every plan once), measured here
    workers: int
    start: float                # seconds to start the workers
    cores: int = field(default_factory=lambda: os.cpu_count() or 1)

    @property
    def here(self) -> float:
        return self.per_run * self.left

    @property
    def parallel(self) -> int:
        return max(1, min(self.workers, self.cores))

    @property
    def on_workers(self) -> float:
        return self.start + self.here / self.parallel / EFFICIENCY

    def worth_the_workers(self) -> bool:
        return self.left > 0 and self.on_workers * MARGIN < self.here

    def note(self, description: str) -> str:
        """The one line that says why the runs stay in this process."""
        total = self.per_run * self.runs
        runs = f"{self.runs} {description} run{'s' if self.runs != 1 else ''}"
        head = f"--workers {self.workers}: {runs} take about {_seconds(total)} here"
        if self.parallel == 1:
            return f"{head}, and this machine has one core: running in this process"
        if total <= self.start:
            return (f"{head}, less than starting {self.workers} workers (about "
                    f"{_seconds(self.start)}): running in this process")
        with_workers = self.per_run * (self.runs - self.left) + self.on_workers
        return (f"{head}; about {_seconds(with_workers)} with {self.workers} workers, "
                f"{_seconds(self.start)} of it to start them: running in this process")


def _seconds(s: float) -> str:
    return f"{s:.1f} s" if s < 10 else f"{s:.0f} s"


def place(runner, tasks: list, runs_in: Callable[[tuple], int], execute: Callable,
          description: str, say: Optional[Callable[[str], None]] = None):
    """Run ``tasks`` (batches) in this process until it is clear where the
    rest should go, and return the runner for the rest and the tasks left.
    ``runner`` is a not yet started :class:`~.cluster.LocalWorkers`;
    ``execute(task)`` runs one batch here (and records it), ``runs_in(task)``
    is how many runs it holds. ``say`` gets the line that says why the runs
    stay here, if they do."""
    from .cluster import InProcess, start_seconds
    if not tasks:
        return InProcess(), tasks
    # CPU time: on a machine others share, waiting for a core is not the
    # study's cost (the workers would wait as long), and the start-up cost
    # is what it is on an idle machine
    t0 = time.process_time()
    execute(tasks[0])
    seconds = time.process_time() - t0
    rest = tasks[1:]
    runs = sum(runs_in(t) for t in tasks)
    projection = Projection(runs, runs - runs_in(tasks[0]), seconds / runs_in(tasks[0]),
                            runner.requested, start_seconds(runner.requested))
    if projection.worth_the_workers():
        return runner.start(), rest
    if say is not None:
        say(projection.note(description))
    return InProcess(), rest
