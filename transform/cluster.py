"""Where an evaluation's runs execute: in this process, on a local Dask
cluster of worker processes, or on an existing Dask distributed cluster
reached through its scheduler (the ``dask scheduler`` / ``dask worker``
commands, or any deployment of them: SSH, SLURM via dask-jobqueue,
Kubernetes; every worker needs htn installed).

A runner executes batches of runs and yields each batch's results as soon as
it finishes, in whatever order. Dask gives the batches of a lost worker to
the others; the caller keys results by run number, so nothing is counted
twice.
"""
from __future__ import annotations

import logging
from contextlib import contextmanager
from typing import Callable, Iterable, Iterator, Optional

from htn.jshop.errors import HtnError


class ClusterError(RuntimeError):
    """The cluster could not complete the runs (not an input error)."""


class InProcess:
    """Runs the batches one after another in this process."""
    workers = 1

    def results(self, function: Callable, batches: Iterable[tuple]) -> Iterator:
        for args in batches:
            yield function(*args)


class DaskRunner:
    """Runs the batches as tasks of a Dask client's cluster."""

    def __init__(self, client):
        self.client = client

    @property
    def workers(self) -> int:
        return len(self.client.scheduler_info()["workers"])

    def results(self, function: Callable, batches: Iterable[tuple]) -> Iterator:
        from distributed import as_completed
        from distributed.scheduler import KilledWorker
        futures = [self.client.submit(function, *args, pure=False) for args in batches]
        try:
            for _, result in as_completed(futures, loop=self.client.loop, with_results=True):
                yield result
        except KilledWorker as exc:
            raise ClusterError(f"a batch of runs was lost with every worker that took it "
                               f"({exc}); giving up") from None
        except ModuleNotFoundError as exc:
            raise ClusterError(f"a Dask worker cannot import {exc.name}: every worker needs "
                               "htn[eval], and htn[sim] for --robot pybullet") from None
        finally:
            for f in futures:
                f.release()


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
        raise HtnError(f"--scheduler {address}: not a Dask scheduler address "
                       f"like tcp://HOST:PORT ({exc})") from None


def _quiet_dask() -> None:
    # Dask logs worker losses and restarts at WARNING; the evaluation
    # survives them, so the user needs only errors
    for name in ("distributed", "distributed.client", "distributed.scheduler",
                 "distributed.nanny", "distributed.worker", "distributed.core"):
        logging.getLogger(name).setLevel(logging.ERROR)


@contextmanager
def open_runner(workers: int = 1, scheduler: Optional[str] = None,
                preload: tuple = ("htn.transform.runs",)):
    """A runner for ``workers`` processes (1: this process; more: a local
    Dask cluster), or for the Dask cluster whose scheduler is at
    ``scheduler``. The scheduler is reached, and has a worker, before this
    returns; otherwise a one-line :class:`HtnError`."""
    if scheduler is None and workers <= 1:
        yield InProcess()
        return
    _quiet_dask()
    import dask
    from distributed import Client, LocalCluster
    if scheduler is not None:
        check_scheduler_address(scheduler)
        timeout = dask.config.get("distributed.comm.timeouts.connect")
        try:
            client = Client(scheduler, timeout=timeout, set_as_default=False)
        except OSError as exc:
            raise HtnError(f"--scheduler {scheduler}: cannot reach the Dask scheduler "
                           f"({exc})") from None
        cluster = None
        try:
            client.wait_for_workers(1, timeout=timeout)
        except TimeoutError:
            client.close()
            raise HtnError(f"--scheduler {scheduler}: the scheduler has no workers "
                           f"(waited {timeout})") from None
    else:
        # the workers' statistical profiler feeds the dashboard, which is not
        # started; sampling the runs' Python stacks every 10 ms slows them
        with dask.config.set({"distributed.worker.profile.enabled": False}):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR,
                                   preload=list(preload))
        client = Client(cluster, set_as_default=False)
    try:
        yield DaskRunner(client)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
