"""Checkpoints of a run: its whole state at a step boundary, written atomically, the last two
kept, for ``perga run --resume RUN``.

A checkpoint holds the simulation, pickled (the machine's Pymunk space with its cached contacts
and the Chipmunk state that pymunk's pickling does not carry exactly, which the machine adds
(:mod:`perga.machine.chipmunk_state`); the contact model's arrays with their tangential springs
and neighbour lists, the process's random-number state, the impacts so far, the energy meter),
and what the runner hands over (the recorders with their files' lengths, the frame clock, the
summary so far).

A run takes its checkpoints on a grid of simulated time (``output.checkpoint_every``) and, at
each, goes on from the checkpoint itself (:func:`read` of the bytes it just wrote), exactly as
a resumed run does: so a run resumed from any of its checkpoints ends with the tables and
frames, bit for bit, of one that never stopped (tests/test_checkpoints.py). That matters for
rigid runs: Chipmunk's broad phase is rebuilt from the pickle, and with it the order in which
the solver takes the contacts, so a rigid run's results depend on the grid (at round-off, which
the chaos of many contacts then amplifies); a soft run's round trip is exact, and its results
do not depend on the grid.

Pickle was chosen over a format of our own because pymunk pickles a space whole, cached contacts
included, which no public pymunk call reads or writes; the price is that a checkpoint is read
only by the perga code that wrote it (checked: :func:`code_version`), and, as with any pickle,
only checkpoints one wrote oneself should be loaded.

A file ``RUN/checkpoints/step-NNNNNNNNNNNN.ckpt`` is a first line ``perga-checkpoint 1 VERSION
SHA256`` (the digest of the rest) and the pickle, written to a temporary file, flushed to the
disk and renamed into place; a file whose digest does not match is passed over for the one
before it.
"""

from __future__ import annotations

import gc
import hashlib
import os
import pickle
from collections.abc import Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path

import perga
from perga.engine.simulation import Simulation
from perga.output import relative_pickle
from perga.output.files import write_all

FORMAT = "perga-checkpoint 1"
KEEP = 2
"""Checkpoints kept: the newest and the one before it."""


@cache
def code_version() -> str:
    """perga's version and a digest of its source files: a checkpoint is read only by the code
    that wrote it (a pickle holds its classes by name, and their fields may change). Taken once
    a process: the sources do not change under a running perga."""
    root = Path(perga.__file__).parent
    digest = hashlib.sha256()
    for source in sorted(root.rglob("*.py")):
        digest.update(source.relative_to(root).as_posix().encode() + b"\0")
        digest.update(source.read_bytes())
    return f"{perga.__version__}+{digest.hexdigest()[:12]}"


class CheckpointError(Exception):
    """No checkpoint that this perga can go on from; the message says why."""


def folder(run: Path) -> Path:
    """Where the run ``run`` keeps its checkpoints."""
    return run / "checkpoints"


@contextmanager
def _no_collection() -> Iterator[None]:
    """Python's cyclic garbage collector held off: (un)pickling makes many objects, and the
    collections they trigger would cost more than the pickling (docs/dev/reliability.md)."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def dump(sim: Simulation, handed_over: dict[str, object], run: Path, case: str) -> bytes:
    """A checkpoint of ``sim`` (now, between steps) and ``handed_over`` (the runner's state, its
    paths taken relative to the run directory ``run``) for the case whose digest is ``case``,
    as the bytes of its file."""
    with _no_collection():
        body = pickle.dumps(
            {
                "case": case,
                "sim": sim,
                "runner": relative_pickle.dumps(handed_over, run),
            },
            protocol=pickle.HIGHEST_PROTOCOL,
        )
    return f"{FORMAT} {code_version()} {hashlib.sha256(body).hexdigest()}\n".encode() + body


def write(run: Path, step: int, data: bytes) -> Path:
    """Write the checkpoint ``data`` taken at ``step`` into the run directory ``run``
    (atomically: a temporary file, flushed to the disk, renamed); remove all but the newest
    :data:`KEEP`."""
    where = folder(run)
    where.mkdir(exist_ok=True)
    path = where / f"step-{step:012d}.ckpt"
    temporary = where / f".{path.name}.tmp"
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    try:
        write_all(fd, data)
        os.fsync(fd)
    except OSError:
        os.close(fd)
        temporary.unlink(missing_ok=True)
        raise
    os.close(fd)
    temporary.replace(path)
    directory = os.open(where, os.O_RDONLY)
    try:
        os.fsync(directory)  # the rename itself on the disk
    finally:
        os.close(directory)
    for old in sorted(where.glob("step-*.ckpt"))[:-KEEP]:
        old.unlink()
    return path


def read(data: bytes, name: str = "checkpoint") -> tuple[Simulation, dict[str, object]]:
    """The simulation in the checkpoint ``data`` (named ``name`` in errors) and the rest of it:
    the case's digest ("case") and the runner's state, still pickled ("runner": unpickling
    recorders reopens their files, :func:`load` does it). CheckpointError if ``data`` is not a
    checkpoint, is damaged or was written by other code."""
    head, _, body = data.partition(b"\n")
    fields = head.decode("utf-8", "replace").split(" ")
    if " ".join(fields[:2]) != FORMAT or len(fields) != 4:
        raise CheckpointError(f"{name}: not a perga checkpoint")
    version, digest = fields[2], fields[3]
    if hashlib.sha256(body).hexdigest() != digest:
        raise CheckpointError(f"{name}: damaged (its digest does not match)")
    if version != code_version():
        raise CheckpointError(f"{name}: written by perga {version}, this is {code_version()}")
    with _no_collection():
        state = pickle.loads(body)
    return state.pop("sim"), state


def load(run: Path, case: str) -> tuple[Simulation, dict[str, object], Path]:
    """The newest usable checkpoint of the run directory ``run`` for the case whose digest is
    ``case``: the simulation, the runner's state (its paths in ``run``; its recorders' files
    cut back to where they stood) and the file. CheckpointError when there is none."""
    paths = sorted(folder(run).glob("step-*.ckpt"), reverse=True)
    if not paths:
        raise CheckpointError(
            f"{run} has no checkpoint ({folder(run)}/step-*.ckpt): a run writes one every "
            "output.checkpoint_every of simulated time"
        )
    problems = []
    for path in paths:
        try:
            sim, rest = read(path.read_bytes(), path.name)
        except CheckpointError as exc:
            problems.append(str(exc))
            continue
        if rest["case"] != case:
            problems.append(f"{path.name}: written for another case than {run / 'case.toml'}")
            continue
        runner = rest["runner"]
        assert isinstance(runner, bytes)
        return sim, relative_pickle.loads(runner, run), path
    raise CheckpointError(f"no checkpoint of {run} can be used: " + "; ".join(problems))
