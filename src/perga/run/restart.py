"""Going on from another run: ``perga run --resume RUN`` (a stopped run, from its newest
checkpoint) and ``perga run CASE --from RUN[:TIME]`` (a case started from a run's granules)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from perga.case import CaseError, load_case
from perga.case.load import overridden, read_case_data
from perga.case.schema import Case
from perga.geometry.clearance import overlapping_pairs
from perga.model.sizes import initial_radii
from perga.output.tables import TableError, read_columns, table_path
from perga.run import checkpoints
from perga.run.summary import FINISHED


class RunStateError(Exception):
    """A run's state cannot be taken (``perga run --from``): the message says why."""


def granules_of_run(run: Path, time: float | None = None) -> tuple[float, list[str], np.ndarray]:
    """The granules of the run directory ``run`` at its last frame at or before ``time`` (s;
    None: its last frame), as case overrides that start a case from them: (the frame's time,
    ``granules.count`` and an explicit ``granules.placement`` with positions, velocities, spins
    and the frame's largest overlap of two granules allowed, their radii, m). RunStateError if
    the run has no granule table or no such frame."""
    path = table_path(run, "granules")
    if path is None:
        raise RunStateError(f"{run} has no granule table (granules.csv or granules.parquet)")
    try:
        table = read_columns(path)
    except TableError as exc:
        raise RunStateError(str(exc)) from None
    except OSError as exc:
        raise RunStateError(f"{path}: cannot read ({exc.strerror or exc})") from None
    times = table["time"]
    chosen = times if time is None else times[times <= time * (1 + 1e-12)]
    if chosen.size == 0:
        raise RunStateError(f"{path}: no frame at or before t = {time} s")
    rows = times == chosen.max()
    x, y, vx, vy, spins = (
        table[c][rows].tolist() for c in ("x", "y", "vx", "vy", "angular_velocity")
    )  # Python floats: their repr is TOML
    overlap = largest_overlap(np.column_stack((x, y)), table["radius"][rows])
    placement = (
        f'{{kind = "explicit", overlap = {overlap!r}, '
        f"positions = [{', '.join(f'[{a!r}, {b!r}]' for a, b in zip(x, y, strict=True))}], "
        f"velocities = [{', '.join(f'[{a!r}, {b!r}]' for a, b in zip(vx, vy, strict=True))}], "
        f"angular_velocities = [{', '.join(repr(w) for w in spins)}]}}"
    )
    overrides = [f"granules.count={int(rows.sum())}", f"granules.placement={placement}"]
    return float(chosen.max()), overrides, table["radius"][rows]


def largest_overlap(positions: np.ndarray, radii: np.ndarray) -> float:
    """The largest overlap of two of the discs, m (0 if none overlap)."""
    pairs = overlapping_pairs(positions, radii)
    if len(pairs) == 0:
        return 0.0
    gap = np.hypot(*(positions[pairs[:, 0]] - positions[pairs[:, 1]]).T)
    return float(np.max(radii[pairs[:, 0]] + radii[pairs[:, 1]] - gap))


def check_resumable(directory: Path) -> None:
    """CheckpointError unless the run in ``directory`` stopped before its end (a run killed
    before it wrote summary.json counts as stopped)."""
    summary = directory / "summary.json"
    try:
        text = summary.read_text(encoding="utf-8") if summary.is_file() else "{}"
        status = json.loads(text).get("status")
    except (OSError, ValueError, AttributeError):
        status = None
    if status in FINISHED:
        raise checkpoints.CheckpointError(f"{directory} {status}: there is nothing to resume")


def case_from_run(case_path: Path, overrides: list[str], start_from: str) -> Case:
    """The case of ``perga run CASE --from RUN[:TIME]``: CASE (with ``overrides``) with its
    granules replaced by RUN's at that frame (:func:`granules_of_run`). RunStateError, naming
    ``--from``, for a bad time, a run without such a frame, or sizes other than CASE's;
    CaseError for a bad case."""
    run, _, time = start_from.rpartition(":")
    try:
        at = float(time) if run else None
    except ValueError:
        run, at = start_from, None  # a ':' in the path, no time
    run = run or start_from
    if at is not None and not (math.isfinite(at) and at >= 0):
        raise RunStateError(f"--from {start_from}: the time must be a number of seconds >= 0")
    try:
        taken, granules, radii = granules_of_run(Path(run), at)
    except RunStateError as exc:
        raise RunStateError(f"--from {start_from}: {exc}") from None
    everything = [*overrides, *granules]
    try:  # the sizes first, from the schema alone: a placement check would blame overlaps
        given = initial_radii(
            Case.model_validate(overridden(read_case_data(case_path), everything, case_path))
        )
    except (CaseError, ValidationError):
        given = radii  # load_case names the problem
    if not np.array_equal(given, radii):
        raise RunStateError(
            f"--from {start_from}: the run's granules at t = {taken} s have radii "
            f"{radii.min():g}-{radii.max():g} m, {case_path} gives {given.min():g}-"
            f"{given.max():g} m (granules.radius or granules.size): the sizes must be the same"
        )
    return load_case(case_path, overrides=everything)
