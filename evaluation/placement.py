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
seconds of the thread that runs them, which is what a run costs on an idle machine.

The workers start in a thread while this process goes on running batches,
and take the batches not yet begun as soon as they are up, so that their
start-up hides behind runs instead of adding to them (a PyBullet run takes
about as long as starting two workers). Nor do they wait for the first
batch to end: they start the moment the CPU time it has taken so far is
enough to make the study worth them (the batch will take at least that).
A study whose runs are known to be long (PyBullet's: a run takes half a
second at the least) and many enough starts them even before, beside its
planning (:func:`start_early`).
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

EFFICIENCY = 0.9  # of each worker, against this process (sending tasks, results)
MARGIN = 1.15  # the workers must be this much faster to be started
SWITCH_INTERVAL = 0.0002  # seconds between GIL hand-overs while the workers start


@dataclass
class Projection:
    """The rest of a study, projected from the batches run so far."""

    runs: int  # runs of the study
    left: float  # runs not yet done (a fraction: some of a run's plans)
    per_run: float  # seconds per run (every plan once), measured here
    workers: int
    start: float  # seconds to start the workers
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
            return (
                f"{head}, less than starting {self.workers} workers (about "
                f"{_seconds(self.start)}): running in this process"
            )
        with_workers = self.per_run * (self.runs - self.left) + self.on_workers
        return (
            f"{head}; about {_seconds(with_workers)} with {self.workers} workers, "
            f"{_seconds(self.start)} of it to start them: running in this process"
        )


def _seconds(s: float) -> str:
    return f"{s:.1f} s" if s < 10 else f"{s:.0f} s"


def place(
    runner,
    tasks: list,
    runs_in: Callable[[tuple], float],
    function: Callable,
    take: Callable[[list], None],
    description: str,
    say: Callable[[str], None] | None = None,
):
    """Run ``tasks`` (batches) in this process until it is clear where the
    rest should go; return the runner for the rest and an iterator over the
    results of the tasks left. ``runner`` is a not yet started
    :class:`~.cluster.LocalWorkers`; ``function(*task)`` runs one batch and
    ``take(results)`` records them; ``runs_in(task)`` is how many runs it
    holds (a fraction: some of a run's plans). ``say`` gets the line that
    says why the runs stay here, if they do. Workers that
    :func:`start_early` began to start get the tasks once up, unmeasured."""
    from .cluster import InProcess, start_seconds

    if not tasks:
        return InProcess(), iter(())
    if getattr(runner, "starting", False):  # started early: no need to measure
        early = _Starter(runner, tasks, function, begun=0)
        early.run_here(take)
        return early.result()
    runs, first = sum(runs_in(t) for t in tasks), runs_in(tasks[0])

    def projection(seconds: float) -> Projection:
        return Projection(
            round(runs),
            runs - first,
            seconds / first,
            runner.requested,
            start_seconds(runner.requested),
        )

    # CPU time of this thread: on a machine others share, waiting for a core
    # is not the study's cost (the workers would wait as long), the start-up
    # cost is what it is on an idle machine, and a starting cluster's thread
    # is not the batch's
    clock = _thread_clock()
    now = time.thread_time if clock is None else lambda: time.clock_gettime(clock)
    t0 = now()
    starter: _Starter | None = None
    if clock is not None:  # another thread can read this one's clock
        starter = _Starter(
            runner,
            tasks,
            function,
            begun=1,
            when=lambda: projection(now() - t0).worth_the_workers(),
        )
    try:
        take(function(*tasks[0]))
    except BaseException:
        if starter is not None:
            starter.stop()
        raise
    seconds = now() - t0
    if starter is not None and not starter.stop():
        starter = None  # the first batch was too short to start them
    if starter is None and projection(seconds).worth_the_workers():
        starter = _Starter(runner, tasks, function, begun=1)
    if starter is not None:
        starter.run_here(take)
        return starter.result()
    if say is not None:
        say(projection(seconds).note(description))
    return InProcess(), InProcess().results(function, tasks[1:])


def start_early(runner, runs: int, plans: int, least: float) -> None:
    """Start ``runner``'s workers now, beside the planning, if the least a
    run of a plan can take (``least`` seconds) already makes the ``runs``
    runs of ``plans`` plans worth them: a PyBullet run takes seconds, and the
    start then hides behind the planning too. Otherwise :func:`place`
    measures first."""
    from .cluster import start_seconds

    if not getattr(runner, "deferred", False) or least <= 0 or runs <= 0:
        return
    projection = Projection(
        runs, runs, least * plans, runner.requested, start_seconds(runner.requested)
    )
    if projection.worth_the_workers():
        runner.start_soon(fast_switching)


_switching = threading.Lock()
_switchers: list[Any] = [0, None]  # threads starting workers; the interval before them


def _switch_fast() -> None:
    """Hand the GIL over every :data:`SWITCH_INTERVAL` while workers start:
    the start is many short steps of Dask's event loop, each waiting for the
    GIL while a run (or the planning) holds it, by default up to 5 ms a
    step, which made starting two workers beside a PyBullet run take 15 s
    instead of 2.5. Calls nest, from any thread: the last
    :func:`_switch_back` restores the interval."""
    with _switching:
        if not _switchers[0]:
            _switchers[1] = sys.getswitchinterval()
            sys.setswitchinterval(SWITCH_INTERVAL)
        _switchers[0] += 1


def _switch_back() -> None:
    with _switching:
        _switchers[0] -= 1
        if not _switchers[0]:
            sys.setswitchinterval(_switchers[1])


@contextmanager
def fast_switching():
    """:func:`_switch_fast` for the time of a ``with`` block."""
    _switch_fast()
    try:
        yield
    finally:
        _switch_back()


def _thread_clock() -> int | None:
    """The CPU-time clock of the calling thread, which another thread can read."""
    try:
        return time.pthread_getcpuclockid(threading.get_ident())
    except (AttributeError, OSError):  # not on this platform
        return None


class _Starter:
    """Starts ``runner``'s workers in a thread (once ``when()`` is true, if
    given) while this process runs the tasks; once they are up, the thread
    hands them every task not yet begun here."""

    POLL = 0.02  # seconds between looks at ``when()``

    def __init__(
        self,
        runner,
        tasks: list,
        function: Callable,
        begun: int,
        when: Callable[[], bool] | None = None,
    ):
        self.runner, self.tasks, self.function = runner, tasks, function
        self.begun = begun  # tasks[:begun] are (being) run here
        self.when = when
        self.lock = threading.Lock()
        self.stopped = threading.Event()
        self.starting = self.switched = False
        self.workers: Any = None  # the runner on the workers, once up
        self.results: Any = None  # the iterator over the results they give
        self.error: BaseException | None = None
        self.thread = threading.Thread(
            target=self._start, name="htn: starting workers", daemon=True
        )
        self.thread.start()

    def _start(self) -> None:
        try:
            while self.when is not None and not self.when():
                if self.stopped.wait(self.POLL):
                    return
            with self.lock:
                if self.stopped.is_set():
                    return
                self.starting = True
            _switch_fast()  # until the caller has joined this thread
            self.switched = True
            workers = self.runner.start()
            with self.lock:
                self.workers = workers
                self.results = workers.submit(self.function, self.tasks[self.begun :])
        except BaseException as exc:  # re-raised in the calling thread
            self.error = exc

    def stop(self) -> bool:
        """Stop waiting to start the workers; whether they are starting (or up)."""
        with self.lock:
            self.stopped.set()
            starting = self.starting
        if not starting:
            self.thread.join()
        return starting

    def run_here(self, take: Callable) -> None:
        """Run tasks here, one at a time, until the workers are up (or have
        failed to start) or no task is left."""
        try:
            while True:
                with self.lock:
                    if (
                        self.workers is not None
                        or self.begun == len(self.tasks)
                        or not self.thread.is_alive()
                    ):
                        return
                    task = self.tasks[self.begun]
                    self.begun += 1
                take(self.function(*task))
        except BaseException:
            # a run failed or a signal stopped it: the caller closes the
            # cluster, which must be started (or have failed) by then
            self._join()
            raise

    def _join(self) -> None:
        self.thread.join()
        if self.switched:
            self.switched = False
            _switch_back()

    def result(self) -> tuple:
        """The runner on the workers and the iterator over the results of
        the tasks they were given."""
        self._join()
        if self.error is not None:
            raise self.error
        return self.workers, self.results
