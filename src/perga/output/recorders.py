"""Recorders: what a run keeps, from frames (:class:`~perga.model.frame.Frame`), triggered by
simulated time, phase-locked: frame k is taken at the first step whose end time reaches
k·every (never "every since the last"), so a run's frames do not drift.

Each recorder is built with the run directory and the system (:class:`~perga.model.spec.
SceneSpec`); ``record(frame, impacts)`` appends a frame, ``impacts`` being every impact the run
has recorded so far (the run's impact table). A table recorder owns one CSV table.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path
from typing import Protocol

import numpy as np

from perga.model.frame import Frame
from perga.model.records import Impact
from perga.model.spec import SceneSpec
from perga.output.tables import Table
from perga.output.vtk import VtkRecorder


class Recorder(Protocol):
    """What the runner needs of a recorder: built as ``Recorder(directory, spec)``,
    ``record(frame, impacts)`` at each frame and ``close()`` at the end of the run, whatever
    ended it."""

    def record(self, frame: Frame, impacts: Sequence[Impact]) -> None:
        """Append what this recorder keeps of ``frame`` and of ``impacts`` (all so far)."""

    def close(self) -> None:
        """Finish the recorder's files (idempotent)."""


class TableRecorder:
    """A recorder that writes one CSV table (``self.table``)."""

    table: Table

    def close(self) -> None:
        """Close the table (idempotent)."""
        self.table.close()


class PhaseLock:
    """Fires at t_k = k·every (s): ``due(t)`` is true once per k, at the first t ≥ t_k."""

    def __init__(self, every: float) -> None:
        if not every > 0:
            raise ValueError(f"every must be > 0 s (got {every})")
        self.every = every
        self.frame = 0

    def due(self, t: float) -> bool:
        """True if frame k is due at time t (then k advances past t)."""
        # a relative tolerance of 1e-9 absorbs round-off in steps·dt against k·every
        if t + 1e-9 * self.every < self.frame * self.every:
            return False
        self.frame = math.floor(t / self.every + 1e-9) + 1
        return True


class GranuleRecorder(TableRecorder):
    """granules.csv: time, id, x, y, vx, vy, angular_velocity, speed (SI)."""

    columns = ("time", "id", "x", "y", "vx", "vy", "angular_velocity", "speed")

    def __init__(self, directory: Path, spec: SceneSpec) -> None:
        self.table = Table(directory / "granules.csv", self.columns)

    def record(self, frame: Frame, impacts: Sequence[Impact]) -> None:
        """Append one frame."""
        g = frame.granules
        p, v, w = g.positions, g.velocities, g.angular_velocities
        speed = np.hypot(v[:, 0], v[:, 1])
        t = frame.time
        self.table.write(
            (t, i, p[i, 0], p[i, 1], v[i, 0], v[i, 1], w[i], speed[i]) for i in range(len(p))
        )


class HammerRecorder(TableRecorder):
    """hammers.csv: time, id, swing_angle, angular_velocity, vx, vy of each hammer's centre of
    mass, and the rotor's angle and angular velocity (id = -1)."""

    columns = ("time", "id", "swing_angle", "angular_velocity", "vx", "vy")

    def __init__(self, directory: Path, spec: SceneSpec) -> None:
        self.table = Table(directory / "hammers.csv", self.columns)

    def record(self, frame: Frame, impacts: Sequence[Impact]) -> None:
        """Append one frame."""
        t, m = frame.time, frame.machine
        alpha, v, spin = m.swing_angles, m.velocities, m.angular_velocities
        rows = [(t, -1, m.rotor_angle, m.rotor_angular_velocity, 0.0, 0.0)]
        rows += [(t, i, alpha[i], spin[i], v[i, 0], v[i, 1]) for i in range(len(alpha))]
        self.table.write(rows)


def _impact_columns() -> tuple[str, ...]:
    """Impact's fields, its vectors split into components (point -> x, y; normal -> nx, ny;
    granule_velocity_before -> vx_before, vy_before)."""
    split = {
        "point": ("x", "y"),
        "normal": ("nx", "ny"),
        "granule_velocity_before": ("vx_before", "vy_before"),
    }
    return tuple(c for f in fields(Impact) for c in split.get(f.name, (f.name,)))


def _impact_row(impact: Impact) -> tuple[object, ...]:
    values = (getattr(impact, f.name) for f in fields(Impact))
    return tuple(c for v in values for c in (v if isinstance(v, tuple) else (v,)))


class ImpactRecorder(TableRecorder):
    """impacts.csv: every granule-hammer impact, one column per field of
    :class:`~perga.model.records.Impact` (SI)."""

    columns = _impact_columns()

    def __init__(self, directory: Path, spec: SceneSpec) -> None:
        self.table = Table(directory / "impacts.csv", self.columns)
        self.written = 0

    def record(self, frame: Frame, impacts: Sequence[Impact]) -> None:
        """Append the impacts recorded since the last call."""
        new = impacts[self.written :]
        self.table.write(_impact_row(i) for i in new)
        self.written += len(new)


class EnergyRecorder(TableRecorder):
    """energy.csv: the cumulative energy ledger at each frame (J)."""

    columns = (
        "time",
        "kinetic",
        "drive_work",
        "contact_dissipation",
        "friction",
        "drag",
        "closure",
    )

    def __init__(self, directory: Path, spec: SceneSpec) -> None:
        self.table = Table(directory / "energy.csv", self.columns)

    def record(self, frame: Frame, impacts: Sequence[Impact]) -> None:
        """Append one frame (its ledger: the run must track energy)."""
        e = frame.energy
        if e is None:
            raise ValueError("energy.csv needs frames with the energy ledger (track_energy)")
        self.table.write(
            [(frame.time, e.kinetic, e.drive_work, e.contact_dissipation, e.friction, e.drag,
              e.closure)]
        )  # fmt: skip


RECORDERS: dict[str, type] = {
    "granules": GranuleRecorder,
    "hammers": HammerRecorder,
    "impacts": ImpactRecorder,
    "energy": EnergyRecorder,
    "vtk": VtkRecorder,
}
"""Recorder class by the name used in the case file's output.record."""
