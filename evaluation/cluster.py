"""Where an evaluation's runs execute: in this process, on a local Dask
cluster of worker processes, or on an existing Dask distributed cluster
reached through its scheduler (the ``dask scheduler`` / ``dask worker``
commands, or any deployment of them: SSH, SLURM via dask-jobqueue,
Kubernetes; the scheduler and every worker need htn installed).

A runner executes batches of runs and yields each batch's results as soon as
it finishes, in whatever order. Dask gives the batches of a lost worker to
the others; the caller keys results by run number, so nothing is counted
twice.
"""

from __future__ import annotations

import logging
import threading
import warnings
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager, nullcontext
from typing import Any

from htn.jshop.language.errors import HtnError


class ClusterError(RuntimeError):
    """The cluster could not complete the runs (not an input error)."""


class InProcess:
    """Runs the batches one after another in this process."""

    workers = 1
    deferred = False
    notes: list = []

    def results(self, function: Callable, batches: Iterable[tuple]) -> Iterator:
        for args in batches:
            yield function(*args)


class DaskRunner:
    """Runs the batches as tasks of a Dask client's cluster."""

    deferred = False

    def __init__(self, client):
        self.client = client
        self.notes: list[str] = []  # one-line warnings about the cluster

    @property
    def workers(self) -> int:
        # the scheduler's count: the per-worker entries are left out of the
        # client's cached copy when a fresh one cannot be fetched
        info = self.client.scheduler_info()
        return info.get("n_workers", len(info["workers"]))

    def results(self, function: Callable, batches: Iterable[tuple]) -> Iterator:
        return self.submit(function, batches)

    def submit(self, function: Callable, batches: Iterable[tuple]) -> Iterator:
        """Send the batches now; an iterator over their results as they finish."""
        futures = [self.client.submit(function, *args, pure=False) for args in batches]
        return self._collect(futures)

    def _collect(self, futures: list) -> Iterator:
        from distributed import as_completed
        from distributed.scheduler import KilledWorker

        try:
            for _, result in as_completed(futures, loop=self.client.loop, with_results=True):
                yield result
        except KilledWorker as exc:
            raise ClusterError(
                f"a batch of runs was lost with every worker that took it ({exc}); giving up"
            ) from None
        except (ImportError, RuntimeError) as exc:
            # e.g. a worker without pybullet, or Dask's "Error during
            # deserialization of the task graph" caused by one
            missing = _missing_module(exc)
            if missing is None:
                raise
            raise ClusterError(f"the Dask cluster cannot import {missing}: {NEEDS}") from None
        finally:
            for f in futures:
                f.release()


NEEDS = "the scheduler and every worker need htn, with its sim extra for --robot pybullet"


def _missing_module(exc: BaseException) -> str | None:
    e: BaseException | None = exc
    while e is not None:
        if isinstance(e, ModuleNotFoundError):
            return e.name
        e = e.__cause__ or e.__context__
    return None


def _lacking_htn(client) -> list[str]:
    """The scheduler and workers of ``client`` that cannot import htn."""
    # a lambda travels by value, so it runs where htn is missing
    probe = lambda: __import__("importlib.util").util.find_spec("htn") is not None  # noqa: E731
    lacking = [address for address, ok in client.run(probe).items() if not ok]
    try:
        if not client.run_on_scheduler(probe):
            lacking.insert(0, "the scheduler")
    except Exception:  # a scheduler may refuse to run code; its error comes later then
        pass
    return lacking


def _version_notes(caught) -> list[str]:
    """Dask's version-mismatch warnings as one line each."""
    notes = []
    for w in caught:
        rows = [
            [c.strip() for c in line.strip("|").split("|")]
            for line in str(w.message).splitlines()
            if line.startswith("|")
        ]
        if len(rows) > 1:
            header = rows[0][1:]
            notes.append(
                "package versions differ on the Dask cluster: "
                + "; ".join(
                    f"{row[0]} " + ", ".join(f"{h.lower()} {v}" for h, v in zip(header, row[1:]))
                    for row in rows[1:]
                )
            )
        else:
            notes.append(" ".join(str(w.message).split()))
    return notes


def check_scheduler_address(address: str) -> None:
    """A Dask address ``PROTOCOL://HOST:PORT`` (e.g. ``tcp://10.0.0.5:8786``)."""
    from distributed.comm import parse_address
    from distributed.comm.addressing import parse_host_port
    from distributed.comm.registry import backends

    try:
        scheme, location = parse_address(address, strict=True)
        if scheme not in backends:
            raise ValueError(f"unknown protocol '{scheme}' (known: {', '.join(backends)})")
        if scheme in ("tcp", "tls", "ws", "wss"):
            host, port = parse_host_port(location)
            if not host or not 0 < port < 65536:
                raise ValueError("expected HOST:PORT")
    except ValueError as exc:
        raise HtnError(
            f"--scheduler {address}: not a Dask scheduler address like tcp://HOST:PORT ({exc})"
        ) from None


def _quiet_dask() -> None:
    # Dask logs worker losses and restarts at WARNING; the evaluation
    # survives them, so the user needs only errors
    for name in (
        "distributed",
        "distributed.client",
        "distributed.scheduler",
        "distributed.nanny",
        "distributed.worker",
        "distributed.core",
    ):
        logging.getLogger(name).setLevel(logging.ERROR)


class LocalWorkers:
    """A local Dask cluster of ``workers`` processes, started only when asked
    (:meth:`start`): :mod:`htn.evaluation.placement` first measures a batch
    in this process and starts the cluster only for a study whose runs take
    longer than starting it. Until then, and if it is never started, the
    runs are this process's (:attr:`workers` is then 1)."""

    deferred = True

    def __init__(self, workers: int, preload: tuple):
        self.requested = workers
        self.preload = preload
        self.notes: list[str] = []
        self.started_in: float | None = None  # seconds the start took
        self._cluster: Any = None  # the distributed.LocalCluster, once started
        self._client: Any = None  # its distributed.Client
        self._runner: DaskRunner | None = None
        self._lock = threading.Lock()
        self._early: threading.Thread | None = None
        self._early_error: BaseException | None = None

    @property
    def starting(self) -> bool:
        """Whether :meth:`start_soon` has begun the start."""
        return self._early is not None

    def start_soon(self, around=nullcontext) -> None:
        """Begin the start in a thread (inside the context ``around()``);
        :meth:`start` waits for it and raises what it raised."""

        def start() -> None:
            try:
                with around():
                    self.start()
            except BaseException as exc:  # re-raised by start()
                self._early_error = exc

        if self._early is None:
            self._early = threading.Thread(target=start, name="htn: starting workers", daemon=True)
            self._early.start()

    @property
    def workers(self) -> int:
        return self.requested if self._runner is not None else 1

    def start(self) -> DaskRunner:
        """Start the workers (once) and return the runner on them."""
        early = self._early
        if early is not None and early is not threading.current_thread():
            early.join()
            if self._early_error is not None:
                raise self._early_error
        with self._lock:
            return self._start()

    def _start(self) -> DaskRunner:
        if self._runner is None:
            import time

            t0 = time.perf_counter()
            self._cluster, self._client = start_local_cluster(self.requested, self.preload)
            # up means registered with the scheduler and running
            try:
                self._client.wait_for_workers(self.requested, timeout=START_TIMEOUT)
            except TimeoutError:
                self.close()
                raise ClusterError(
                    f"{self.requested} local workers were not up after {START_TIMEOUT} s"
                ) from None
            self._runner = DaskRunner(self._client)
            self.started_in = time.perf_counter() - t0
        return self._runner

    def results(self, function: Callable, batches: Iterable[tuple]) -> Iterator:
        return self.start().results(function, batches)

    def close(self) -> None:
        if self._early is not None:
            self._early.join()  # a cluster still starting is closed once up
        if self._client is not None:
            # a study stopped midway (Ctrl-C, --timeout) cancels the work the
            # scheduler is taking in, which it logs as an error as its loop
            # ends, after close() has returned: no error of the user's. The
            # next cluster's start sets the level back (_quiet_dask)
            for name in (
                "distributed",
                "distributed.scheduler",
                "distributed.client",
                "distributed.core",
            ):
                logging.getLogger(name).setLevel(logging.CRITICAL)
            self._client.close()
            self._cluster.close()
        self._cluster = self._client = self._runner = None


# What starting a local cluster in a fresh process costs on an idle machine, in
# seconds: about START_BASE + START_PER_WORKER x workers. Measured on 2 cores
# (benchmarks/bench_evaluate.py --startup, and the CPU time of the processes
# involved): this process imports Dask (about 1 s of CPU), the server the
# workers are forked from imports Dask and htn (about 1 s), each worker is
# forked and registers with the scheduler (a few tenths), and closing them
# takes 0.1-0.4 s. On a busy machine all of it takes longer, as the runs do.
START_BASE = 2.0
START_PER_WORKER = 0.25
START_TIMEOUT = 120  # seconds the workers may take to be up, on a machine ever so busy


def start_seconds(workers: int) -> float:
    """About how long starting (and closing) a local cluster of ``workers`` takes."""
    return START_BASE + START_PER_WORKER * workers


def start_local_cluster(workers: int, preload: tuple = ("htn.evaluation.runs",)):
    """A local Dask cluster of ``workers`` single-threaded processes and its
    client. The processes are forked from a server process that has imported
    Dask and htn once (multiprocessing's forkserver, where the platform has
    it) instead of each starting an interpreter and importing them again:
    that is most of the cost of starting them."""
    _quiet_dask()
    import multiprocessing

    import dask
    from distributed import Client
    from distributed import LocalCluster as DaskLocalCluster

    settings: dict[str, object] = {
        # the workers' statistical profiler feeds the dashboard, which is not
        # started; sampling the runs' Python stacks every 10 ms slows them
        "distributed.worker.profile.enabled": False
    }
    if "forkserver" in multiprocessing.get_all_start_methods():
        settings["distributed.worker.multiprocessing-method"] = "forkserver"
    with dask.config.set(settings):
        if "distributed.worker.multiprocessing-method" in settings:
            _preload_forkserver(preload)
        cluster = DaskLocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
            preload=list(preload),
            # no dashboard; its HTTP server on any free port, not on 8787, so that
            # two evaluations at once do not warn about the port
            scheduler_kwargs={"dashboard": False, "dashboard_address": ":0"},
        )
    return cluster, Client(cluster, set_as_default=False)


def _preload_forkserver(preload: tuple) -> None:
    # Dask sets the server's preload (itself and the packages it uses) the
    # first time it asks for the context; htn's modules join that list
    import importlib.util

    from distributed.utils import get_mp_context
    from distributed.versions import optional_packages, required_packages

    context = get_mp_context()
    modules = [
        "distributed",
        *(
            p
            for p in (*required_packages, *optional_packages)
            if importlib.util.find_spec(p) is not None
        ),
        *preload,
    ]
    context.set_forkserver_preload(list(dict.fromkeys(modules)))


@contextmanager
def open_runner(
    workers: int = 1, scheduler: str | None = None, preload: tuple = ("htn.evaluation.runs",)
):
    """A runner for ``workers`` processes (1: this process; more: a local
    Dask cluster, started when a study is worth it, see :class:`LocalWorkers`),
    or for the Dask cluster whose scheduler is at ``scheduler``. The
    scheduler is reached, and has a worker, before this returns; otherwise a
    one-line :class:`HtnError`."""
    if scheduler is None and workers <= 1:
        yield InProcess()
        return
    if scheduler is None:
        local = LocalWorkers(workers, preload)
        try:
            yield local
        finally:
            local.close()
        return
    _quiet_dask()
    import dask
    from distributed import Client

    check_scheduler_address(scheduler)
    timeout = dask.config.get("distributed.comm.timeouts.connect")
    from distributed.versions import VersionMismatchWarning

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", VersionMismatchWarning)
            client = Client(scheduler, timeout=timeout, set_as_default=False)
    except OSError as exc:
        raise HtnError(
            f"--scheduler {scheduler}: cannot reach the Dask scheduler ({exc})"
        ) from None
    try:
        client.wait_for_workers(1, timeout=timeout)
        lacking = _lacking_htn(client)
    except TimeoutError:
        client.close()
        raise HtnError(
            f"--scheduler {scheduler}: the scheduler has no workers (waited {timeout})"
        ) from None
    if lacking:
        client.close()
        raise HtnError(
            f"--scheduler {scheduler}: htn is not installed on {', '.join(lacking)}; {NEEDS}"
        )
    try:
        runner = DaskRunner(client)
        runner.notes = _version_notes(caught)
        yield runner
    finally:
        client.close()
