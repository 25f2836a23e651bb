"""Recorders: what a run keeps, from frames (:class:`~perga.model.frame.Frame`), triggered by
simulated time, phase-locked: frame k is taken at the first step whose end time reaches
k·every (never "every since the last"), so a run's frames do not drift.

Each recorder is built with the run directory and the system (:class:`~perga.model.system.
System`); ``record(frame, events)`` appends a frame, ``events`` being everything the run has
recorded so far (:class:`~perga.model.records.Events`: impacts, releases, departures). A table
recorder owns one CSV table, written as Parquet at the end of a complete run with
``output.tables = "parquet"``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path
from typing import Protocol

import numpy as np

from perga.contact.laws import contact_law
from perga.model.frame import Frame
from perga.model.records import Contact, Departure, Events, Impact, Release
from perga.model.system import System
from perga.output.tables import ParquetTable, Table, open_table
from perga.output.vtk import VtkRecorder


class Recorder(Protocol):
    """What the runner needs of a recorder: built as ``Recorder(directory, spec)``,
    ``record(frame, events)`` at each frame and ``close(complete)`` at the end of the run,
    whatever ended it; pickled with a checkpoint, it goes on from the state its files had then
    (:mod:`perga.run.checkpoints`)."""

    def record(self, frame: Frame, events: Events) -> None:
        """Append what this recorder keeps of ``frame`` and of ``events`` (all so far)."""

    def close(self, complete: bool = True) -> None:
        """Finish the recorder's files (idempotent); ``complete``: the run ended as planned
        (else it may be resumed: keep what going on needs)."""


class TableRecorder:
    """A recorder that writes one CSV table (``self.table``)."""

    table: Table | ParquetTable
    tables: str = "csv"
    """The table's form once the run is complete: 'csv', or 'parquet' (``NAME.parquet``
    written at :meth:`close`; a run that stops keeps its CSV, which ``--resume`` appends to)."""

    def close(self, complete: bool = True) -> None:
        """Close the table (idempotent; whole rows only, complete or not); complete, with
        :attr:`tables` 'parquet', also write its Parquet form (:meth:`~perga.output.tables.
        Table.write_parquet`)."""
        if complete and self.tables == "parquet":
            self.table.write_parquet()
        else:
            self.table.close()


class PhaseLock:
    """Fires at t_k = k·every (s): ``due(t)`` is true once per k, at the first t ≥ t_k."""

    def __init__(self, every: float) -> None:
        if not every > 0:
            raise ValueError(f"every must be > 0 s (got {every})")
        self.every = every
        self.frame = 0

    def is_due(self, t: float) -> bool:
        """Whether the next frame is due at time t (k does not advance)."""
        return not self._early(t)

    def due(self, t: float) -> bool:
        """True if frame k is due at time t (then k advances past t)."""
        if self._early(t):
            return False
        self.frame = math.floor(t / self.every + 1e-9) + 1
        return True

    def steps_to_next(self, step: int, dt: float) -> int:
        """The steps of ``dt`` (s) from step ``step`` to the first step n whose time n·dt makes
        the next frame due (at least 1); :meth:`due` is not called."""
        n = max(step + 1, math.floor(self.frame * self.every * (1.0 - 2e-9) / dt) - 1)
        while self._early(n * dt):
            n += 1
        return n - step

    def _early(self, t: float) -> bool:
        """Whether ``t`` is before the next frame's time; a relative tolerance of 1e-9 absorbs
        round-off in steps·dt against k·every."""
        return t + 1e-9 * self.every < self.frame * self.every


class GranuleRecorder(TableRecorder):
    """granules.csv: time, id, x, y, vx, vy, angular_velocity, speed, radius, mass (SI); with
    held granules in the system also ``held`` (1 while in its cell), with damage ``survival``
    (expected, -), ``broken`` (1 if drawn broken) and ``damaging_impacts`` (its impacts above
    W_min: the k of the master curve). ``table_format`` 'parquet' writes the same columns as
    the Parquet dataset granules.parquet (:class:`~perga.output.tables.ParquetTable`)."""

    def __init__(self, directory: Path, spec: System, table_format: str = "csv") -> None:
        self.held = spec.has_bonds
        self.damage = spec.process.damage is not None
        columns = ["time", "id", "x", "y", "vx", "vy", "angular_velocity", "speed", "radius"]
        columns += ["mass"] + ["held"] * self.held
        columns += ["survival", "broken", "damaging_impacts"] * self.damage
        integers = {"id", "held", "broken", "damaging_impacts"} & set(columns)
        self.table = open_table(directory / "granules.csv", columns, table_format, integers)

    def record(self, frame: Frame, events: Events) -> None:
        """Append one frame."""
        g = frame.granules
        p, v = g.positions, g.velocities
        columns = [
            np.full(len(p), frame.time),
            g.ids,
            p[:, 0],
            p[:, 1],
            v[:, 0],
            v[:, 1],
            g.angular_velocities,
            np.hypot(v[:, 0], v[:, 1]),
            g.radii,
            g.masses,
        ]
        if self.held:
            columns.append(g.held.astype(np.int64))
        if self.damage:
            columns += [g.survival, g.broken.astype(np.int64), g.damaging_impacts]
        self.table.write_columns(columns)


class HammerRecorder(TableRecorder):
    """hammers.csv: time, id, swing_angle, angular_velocity, vx, vy of each hammer's centre of
    mass, and the rotor's angle and angular velocity (id = -1)."""

    columns = ("time", "id", "swing_angle", "angular_velocity", "vx", "vy")

    def __init__(self, directory: Path, spec: System) -> None:
        self.table = Table(directory / "hammers.csv", self.columns, integers=("id",))

    def record(self, frame: Frame, events: Events) -> None:
        """Append one frame."""
        t, m = frame.time, frame.machine
        alpha, v, spin = m.swing_angles, m.velocities, m.angular_velocities
        rows = [(t, -1, m.rotor_angle, m.rotor_angular_velocity, 0.0, 0.0)]
        rows += [(t, i, alpha[i], spin[i], v[i, 0], v[i, 1]) for i in range(len(alpha))]
        self.table.write(rows)


DAMAGE_FIELDS = ("breakage_probability", "survival")
"""The impact fields only a scene with damage gives."""

SPLIT = {
    "point": ("x", "y"),
    "normal": ("nx", "ny"),
    "granule_velocity_before": ("vx_before", "vy_before"),
    "granule_velocity_after": ("vx_after", "vy_after"),
    "hammer_centre_before": ("hammer_x_before", "hammer_y_before"),
    "position_start": ("x_start", "y_start"),
    "velocity_start": ("vx_start", "vy_start"),
    "position_end": ("x_end", "y_end"),
    "velocity_end": ("vx_end", "vy_end"),
}
"""Vector fields of the records and their columns."""


def record_fields(record: type, omit: frozenset[str] = frozenset()) -> tuple[str, ...]:
    """A record class's field names but ``omit``, in order."""
    return tuple(f.name for f in fields(record) if f.name not in omit)


def record_integers(record: type) -> frozenset[str]:
    """A record class's fields of whole numbers (int or bool), which are columns of their own."""
    return frozenset(f.name for f in fields(record) if f.type in ("int", "bool", int, bool))


def record_columns(record: type, omit: frozenset[str] = frozenset()) -> tuple[str, ...]:
    """A record class's fields but ``omit`` as columns, vectors split into components
    (``SPLIT``)."""
    return tuple(c for name in record_fields(record, omit) for c in SPLIT.get(name, (name,)))


def record_row(record: object, names: tuple[str, ...]) -> list[object]:
    """One record's values of the fields ``names`` (``record_fields``), in the order of
    ``record_columns``: vectors split, booleans as 0/1."""
    row: list[object] = []
    for name in names:
        value = getattr(record, name)
        for c in value if isinstance(value, tuple) else (value,):
            row.append(int(c) if isinstance(c, bool) else c)
    return row


class EventRecorder(TableRecorder):
    """A table of one kind of event (``kind``: the name of its list in
    :class:`~perga.model.records.Events`, ``record_type`` its class), appended as they come."""

    kind: str
    record_type: type
    file: str

    def __init__(self, directory: Path, spec: System) -> None:
        self.omit = self.omitted(spec)
        self.names = record_fields(self.record_type, self.omit)
        columns = record_columns(self.record_type, self.omit)
        integers = record_integers(self.record_type) & set(columns)
        self.table = Table(directory / self.file, columns, integers)
        self.written = 0

    @staticmethod
    def omitted(spec: System) -> frozenset[str]:
        """Fields the scene does not give (none by default)."""
        return frozenset()

    def record(self, frame: Frame, events: Events) -> None:
        """Append the events recorded since the last call."""
        new: Sequence[object] = getattr(events, self.kind)[self.written :]
        self.table.write(record_row(e, self.names) for e in new)
        self.written += len(new)


class ImpactRecorder(EventRecorder):
    """impacts.csv: every granule-hammer impact, one column per field of
    :class:`~perga.model.records.Impact` (SI)."""

    kind, record_type, file = "impacts", Impact, "impacts.csv"

    @staticmethod
    def omitted(spec: System) -> frozenset[str]:
        """The breakage columns, unless the scene has damage; the peak force, unless its
        contacts are soft, and the peak pressure, unless they are Hertz's."""
        omit = set() if spec.process.damage else set(DAMAGE_FIELDS)
        model = spec.contact_model.model
        if model == "impulse":
            omit |= {"peak_force", "peak_pressure"}
        elif not contact_law(model).peak_pressure:
            omit.add("peak_pressure")
        return frozenset(omit)


class ContactRecorder(EventRecorder):
    """contacts.csv: every granule-hammer contact when it ends, one column per field of
    :class:`~perga.model.records.Contact` (SI); written with impacts.csv."""

    kind, record_type, file = "contacts", Contact, "contacts.csv"


class ReleaseRecorder(EventRecorder):
    """releases.csv: every granule pulled out of its cell (:class:`~perga.model.records.
    Release`: time, granule, force; SI)."""

    kind, record_type, file = "releases", Release, "releases.csv"


class OutflowRecorder(EventRecorder):
    """outflow.csv: every granule gone through the outlet (:class:`~perga.model.records.
    Departure`; SI)."""

    kind, record_type, file = "departures", Departure, "outflow.csv"


class EnergyRecorder(TableRecorder):
    """energy.csv: the energy ledger at each frame (:class:`~perga.model.records.
    EnergyLedger`, J; its closure = residual / energy_in_play, dimensionless): the kinetic
    energy of every moving body and the elastic energy stored in the soft contacts now (0 with
    rigid contacts), the other terms cumulative since t = 0, so that a row's residual follows
    from its terms and the first row's (t = 0) kinetic and elastic energy
    (:meth:`~perga.model.records.LedgerTerms.close`)."""

    columns = (
        "time",
        "kinetic",
        "elastic",
        "drive_work",
        "gravity_work",
        "contact_dissipation",
        "friction",
        "drag",
        "inflow",
        "outflow",
        "joint_correction",
        "residual",
        "energy_in_play",
        "closure",
    )

    def __init__(self, directory: Path, spec: System) -> None:
        self.table = Table(directory / "energy.csv", self.columns)

    def record(self, frame: Frame, events: Events) -> None:
        """Append one frame (its ledger: the run must track energy)."""
        e = frame.energy
        if e is None:
            raise ValueError("energy.csv needs frames with the energy ledger (track_energy)")
        self.table.write(
            [(frame.time, e.kinetic, e.elastic, e.drive_work, e.gravity_work,
              e.contact_dissipation, e.friction, e.drag, e.inflow, e.outflow,
              e.joint_correction, e.residual, e.energy_in_play, e.closure)]
        )  # fmt: skip


RECORDERS: dict[str, type] = {
    "granules": GranuleRecorder,
    "hammers": HammerRecorder,
    "impacts": ImpactRecorder,
    "energy": EnergyRecorder,
    "releases": ReleaseRecorder,
    "outflow": OutflowRecorder,
    "vtk": VtkRecorder,
}
"""Recorder class by the name used in the case file's output.record."""

COMPANIONS: dict[str, tuple[type, ...]] = {"impacts": (ContactRecorder,)}
"""Recorders that come with a name of output.record: contacts.csv with impacts.csv."""


def make_recorders(
    names: Sequence[str],
    directory: Path,
    spec: System,
    granule_table: str = "csv",
    tables: str = "csv",
) -> list[Recorder]:
    """The recorders ``names`` (keys of :data:`RECORDERS`) and their :data:`COMPANIONS` for a
    run into ``directory``; the granule table in ``granule_table`` format ('csv' or
    'parquet') while the run goes, the tables in ``tables`` form once it is complete
    (:attr:`TableRecorder.tables`)."""
    if tables not in ("csv", "parquet"):
        raise ValueError(f"tables must be 'csv' or 'parquet' (got {tables!r})")
    recorders: list[Recorder] = []
    for name in names:
        if name == "granules":
            recorders.append(GranuleRecorder(directory, spec, granule_table))
        else:
            recorders.append(RECORDERS[name](directory, spec))
        recorders += [companion(directory, spec) for companion in COMPANIONS.get(name, ())]
    for recorder in recorders:
        if isinstance(recorder, TableRecorder):
            recorder.tables = tables
    return recorders
