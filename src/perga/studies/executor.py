"""Where a study's runs execute: a Dask cluster (``dask.distributed``).

By default a ``LocalCluster`` of worker processes on loopback, one thread each and numba on one
thread (each run sets it, :func:`perga.studies.jobs.run_job`), as many workers as the machine
has free cores (``perga.cores``: its cores less what other processes use, at least one). Given
a scheduler's address, the runs go to that cluster instead (one started with ``dask scheduler``
/ ``dask worker``, or by ``dask-jobqueue`` on SLURM or PBS: start it there and pass its
address); given a ``dask.distributed.Client``, to that client's cluster. The run directories
must be on a file system the workers and this process share.

:func:`run_missing` hands over the rows of the runs found finished (by key,
:mod:`perga.studies.jobs`) and runs the others; :func:`execute` submits every job, hands each
finished row to a callback as it arrives and returns when all are done. A worker that dies
mid-run is the scheduler's concern: its runs go to another worker; rows already received are
kept. Ctrl-C cancels what has not finished and raises KeyboardInterrupt after the rows received
so far were handed over (one that Python swallowed in a callback of ``distributed``'s is raised
after the next row, :func:`perga.stopping.raise_swallowed`).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from distributed import Client, LocalCluster, as_completed

from perga.cores import free_cores
from perga.stopping import raise_swallowed
from perga.studies.jobs import Job, failed_row, finished_row, run_job

Progress = Callable[[int, int], None]
"""progress(runs done, runs in all)."""

WORKER_ENV = {"OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
"""Environment of local workers: BLAS on one thread. Not ``NUMBA_NUM_THREADS``: Dask's Nanny sets
``env`` after the spawned worker has imported the main script, so numba imported by that script
has read its thread count already, and a different one in the environment makes every compile
after numba's threads started fail (tests/studies/test_executor.py)."""


@contextlib.contextmanager
def dask_client(
    client: Client | None = None, scheduler: str | None = None, workers: int | None = None
) -> Iterator[Client]:
    """The client to run on: ``client`` itself, one connected to ``scheduler``, or a new local
    cluster of ``workers`` processes (default :func:`free_cores`), closed on exit."""
    if client is not None:
        yield client
        return
    if scheduler is not None:
        with Client(scheduler) as remote:
            yield remote
        return
    n = workers or free_cores()
    with (
        LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=None,
            env=WORKER_ENV,
        ) as cluster,
        Client(cluster) as local,
    ):
        yield local


def execute(
    client: Client,
    jobs: Sequence[Job],
    on_row: Callable[[dict[str, Any]], None],
    function: Callable[[Job], dict[str, Any]] = run_job,
) -> None:
    """Run ``jobs`` on ``client``'s cluster, calling ``on_row(row)`` in this process for each as
    it finishes (module doc for failures and Ctrl-C)."""
    if not jobs:
        return
    futures = client.map(function, list(jobs), pure=False, key=[f"run-{j.key}" for j in jobs])
    job_of = {f.key: j for f, j in zip(futures, jobs, strict=True)}
    try:
        for future in as_completed(futures):
            if future.status == "error":  # e.g. its workers kept dying: a failed row
                on_row(failed_row(job_of[future.key], repr(future.exception())))
            else:
                on_row(future.result())
            raise_swallowed()
    except BaseException:
        client.cancel(futures)
        raise


def run_missing(
    jobs: Sequence[Job],
    on_row: Callable[[dict[str, Any]], None],
    *,
    client: Client | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
    function: Callable[[Job], dict[str, Any]] = run_job,
) -> int:
    """Call ``on_row(row)`` for every job and return how many ran now: first the rows of the
    runs found finished (a failed one runs again only with ``retry_failed``), then, as they
    finish, those of the others, ``function(job)`` each (a run), on ``client``, the cluster at
    ``scheduler`` or a local cluster of ``workers`` processes (:func:`dask_client`).
    ``progress(done, total)`` once the finished runs are found and after each row that
    arrives."""
    todo = []
    for job in jobs:
        row = finished_row(job)
        if row is not None and (row["status"] == "ok" or not retry_failed):
            on_row(row)
        else:
            todo.append(job)
    done = len(jobs) - len(todo)
    if progress:
        progress(done, len(jobs))

    def arrived(row: dict[str, Any]) -> None:
        nonlocal done
        done += 1
        on_row(row)
        if progress:
            progress(done, len(jobs))

    if todo:
        with dask_client(client, scheduler, workers) as c:
            execute(c, todo, arrived, function)
    return len(todo)
