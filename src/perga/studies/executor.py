"""Where a study's runs execute: a Dask cluster (``dask.distributed``).

By default a ``LocalCluster`` of worker processes on loopback, one thread each and numba on one
thread (each run sets it, :func:`perga.studies.jobs.run_job`), as many workers as the machine
has free cores (``perga.cores``: its cores less what other processes use, at least one). Given
a scheduler's address, the runs go to that cluster instead (one started with ``dask scheduler``
/ ``dask worker``); given a :class:`BatchCluster` (a cluster file, :func:`read_batch_cluster`),
to workers that ``dask-jobqueue`` submits as SLURM or PBS jobs for the study and stops after it;
given a ``dask.distributed.Client``, to that client's cluster. The run directories must be on a
file system the workers and this process share.

:func:`run_missing` hands over the rows of the runs found finished (by key,
:mod:`perga.studies.jobs`) and runs the others; :func:`execute` submits every job, hands each
finished row to a callback as it arrives and returns when all are done. A worker that dies
mid-run is the scheduler's concern: its runs go to another worker; rows already received are
kept. A run executes under an exclusive lock on its key (:func:`run_once`), and a run found
finished ok there is read back, not run: the run of a worker that leaves at its lifetime (or is
lost) goes to another worker, which starts it only once the first process has ended or
finished it, so no finished run is lost or run twice and no two write one run directory.
Ctrl-C cancels what has not finished and raises KeyboardInterrupt after the rows received so far
were handed over (one that Python swallowed in a callback of ``distributed``'s is raised after
the next row, :func:`perga.stopping.raise_swallowed`).
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import re
import tomllib
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, Literal, Self

from dask.utils import parse_bytes, parse_timedelta
from distributed import Client, LocalCluster, as_completed
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from perga.case.names import unknown_key
from perga.case.overrides import parse_toml
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


WALLTIME = re.compile(r"^(\d+):([0-5]\d):([0-5]\d)$")
"""A batch job's wall time, HH:MM:SS (hours may pass 24), as SLURM and PBS both read it."""

CLUSTER_CLASSES = {"slurm": "SLURMCluster", "pbs": "PBSCluster"}
"""dask-jobqueue's cluster class of each batch system."""


class BatchCluster(BaseModel):
    """A cluster file (TOML): Dask workers as batch jobs of SLURM or PBS, submitted by
    dask-jobqueue for one study and cancelled after it. ``jobs`` jobs at a time, each of
    ``cores`` cores running ``processes`` worker processes (one thread each unless fewer
    processes than cores); a worker leaves after ``lifetime`` ± ``lifetime_stagger`` (before the
    wall time kills it) and a new job replaces it while runs remain. Keys not given here come
    from dask-jobqueue's configuration (``~/.config/dask/jobqueue.yaml``); relative paths are
    the file's folder's."""

    model_config = ConfigDict(extra="forbid")

    system: Literal["slurm", "pbs"]
    jobs: int = Field(1, ge=1)
    cores: int = Field(ge=1)
    processes: int | None = Field(None, ge=1)
    memory: str
    walltime: str
    lifetime: str | None = None
    lifetime_stagger: str | None = None
    queue: str | None = None
    account: str | None = None
    interface: str | None = None
    prologue: list[str] = []
    directives: list[str] = []
    log_directory: Path | None = None

    @field_validator("memory")
    @classmethod
    def _memory(cls, value: str) -> str:
        try:
            size = parse_bytes(value)
        except ValueError:
            size = 0
        if size <= 0:
            raise ValueError("a size above 0 such as '4GB'")
        return value

    @field_validator("walltime")
    @classmethod
    def _walltime(cls, value: str) -> str:
        if not WALLTIME.match(value) or seconds(value) <= 0:
            raise ValueError("HH:MM:SS, above 00:00:00")
        return value

    @field_validator("lifetime", "lifetime_stagger")
    @classmethod
    def _duration(cls, value: str | None) -> str | None:
        try:
            parse_timedelta(value)
        except (KeyError, ValueError, TypeError):
            raise ValueError("a duration such as '50m', '90s' or '1h'") from None
        return value

    @model_validator(mode="after")
    def _fits(self) -> Self:
        if self.processes is not None and self.processes > self.cores:
            raise ValueError(f"processes: 1 to cores ({self.cores}) (got {self.processes})")
        life, stagger, wall = self.lifetimes()
        if not 0 <= stagger < life or life + stagger >= wall:
            raise ValueError(
                f"lifetime ± lifetime_stagger: 0 <= stagger < lifetime and lifetime + stagger "
                f"below the walltime ({wall:g} s) (got {life:g} s ± {stagger:g} s)"
            )
        return self

    def lifetimes(self) -> tuple[float, float, float]:
        """A worker's lifetime and its stagger (default 0.9 and 0.05 of the wall time) and the
        wall time, s."""
        wall = seconds(self.walltime)
        life = parse_timedelta(self.lifetime) if self.lifetime else 0.9 * wall
        stagger = parse_timedelta(self.lifetime_stagger) if self.lifetime_stagger else 0.05 * wall
        return float(life), float(stagger), wall

    def options(self) -> dict[str, Any]:
        """The keyword arguments of dask-jobqueue's cluster class."""
        life, stagger, _ = self.lifetimes()
        given = {
            "cores": self.cores,
            "processes": self.processes or self.cores,
            "memory": self.memory,
            "walltime": self.walltime,
            "queue": self.queue,
            "account": self.account,
            "interface": self.interface,
            "log_directory": str(self.log_directory) if self.log_directory else None,
            "job_extra_directives": self.directives or None,
        }
        return {k: v for k, v in given.items() if v is not None} | {
            "job_script_prologue": [f"export {k}={v}" for k, v in WORKER_ENV.items()]
            + self.prologue,
            "worker_extra_args": [
                "--lifetime",
                f"{life:g}s",
                "--lifetime-stagger",
                f"{stagger:g}s",
            ],
        }


def seconds(walltime: str) -> float:
    """A wall time HH:MM:SS in seconds."""
    hours, minutes, secs = (int(part) for part in walltime.split(":"))
    return float(3600 * hours + 60 * minutes + secs)


def read_batch_cluster(path: str | Path) -> BatchCluster:
    """The cluster file ``path`` (:class:`BatchCluster`); ValueError naming the file and each
    bad key with what it allows."""
    path = Path(path)
    try:
        data = parse_toml(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ValueError(f"{path}: not a readable TOML file ({exc})") from None
    try:
        batch = BatchCluster.model_validate(data)
    except ValidationError as exc:
        raise ValueError("; ".join(f"{path}: {_describe(e)}" for e in exc.errors())) from None
    if batch.log_directory is not None:
        batch = batch.model_copy(update={"log_directory": path.parent / batch.log_directory})
    return batch


def _describe(error: Any) -> str:
    """One pydantic error of a cluster file: the key, what it allows, what it got."""
    key = ".".join(str(p) for p in error["loc"]) or "(top level)"
    if error["type"] == "extra_forbidden":
        return f"{key}: {unknown_key(key, list(BatchCluster.model_fields))}"
    message = error["msg"].removeprefix("Value error, ")
    if not error["loc"]:  # a rule between keys: its message names them and their values
        return message
    got = f" (got {error['input']!r})" if error["type"] != "missing" else ""
    return f"{key}: {message}{got}"


@contextlib.contextmanager
def batch_client(batch: BatchCluster) -> Iterator[Client]:
    """A client of a new dask-jobqueue cluster as ``batch`` says, adaptive at ``batch.jobs``
    jobs (so a job whose workers left at their lifetime is replaced), closed on exit (its jobs
    cancelled)."""
    import dask_jobqueue

    kind = getattr(dask_jobqueue, CLUSTER_CLASSES[batch.system])
    with kind(**batch.options()) as cluster, Client(cluster) as client:
        cluster.adapt(minimum_jobs=batch.jobs, maximum_jobs=batch.jobs)
        yield client


@contextlib.contextmanager
def dask_client(
    client: Client | None = None,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
) -> Iterator[Client]:
    """The client to run on: ``client`` itself, one connected to ``scheduler`` (an address) or
    of the batch cluster it describes, or a new local cluster of ``workers`` processes
    (default :func:`free_cores`), closed on exit."""
    if client is not None:
        yield client
        return
    if isinstance(scheduler, BatchCluster):
        with batch_client(scheduler) as batch:
            yield batch
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
    once = functools.partial(run_once, function=function)
    futures = client.map(once, list(jobs), pure=False, key=[f"run-{j.key}" for j in jobs])
    job_of = {f.key: j for f, j in zip(futures, jobs, strict=True)}
    try:
        for future in as_completed(futures):
            if future.status == "error":  # e.g. its workers kept dying: a failed row
                on_row(failed_row(job_of[future.key], repr(future.exception())))
            else:
                on_row(future.result())
            future.release()  # a worker leaving holds no row the study still needs
            raise_swallowed()
    except BaseException:
        client.cancel(futures)
        raise


def run_once(job: Job, function: Callable[[Job], dict[str, Any]] = run_job) -> dict[str, Any]:
    """``function(job)`` under an exclusive lock on the run's key (``fcntl.lockf`` on
    DIRECTORY.lock beside the run directory, dropped by the OS however the holder ends), or the
    run's row if it is found finished ok once the lock is held (module doc)."""
    lock = Path(f"{job.directory}.lock")
    lock.parent.mkdir(parents=True, exist_ok=True)
    with lock.open("a") as handle:
        fcntl.lockf(handle, fcntl.LOCK_EX)
        row = finished_row(job)
        if row is not None and row["status"] == "ok":
            return row
        return function(job)


def run_missing(
    jobs: Sequence[Job],
    on_row: Callable[[dict[str, Any]], None],
    *,
    client: Client | None = None,
    scheduler: str | BatchCluster | None = None,
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
