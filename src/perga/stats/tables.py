"""A run directory's tables as numpy columns (SI units, as written by perga.output)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from perga.case import load_case
from perga.case.schema import Case
from perga.output.tables import read_run_table, table_path

FloatArray = NDArray[np.float64]
Columns = dict[str, FloatArray]

TABLES = ("granules", "hammers", "impacts", "contacts", "energy")
"""The run tables :class:`Run` reads."""


def read_table(path: Path) -> Columns:
    """The run table ``path`` names (``RUN/NAME.csv`` or ``RUN/NAME.parquet``), whichever form
    the run has, as {column: float array}; empty columns if no rows
    (:func:`perga.output.tables.read_run_table`)."""
    return read_run_table(path.parent, path.stem)


@dataclass(frozen=True)
class Run:
    """One run directory: its case, summary and tables (absent tables are empty dicts)."""

    directory: Path
    case: Case
    summary: dict[str, object]
    granules: Columns = field(repr=False)
    hammers: Columns = field(repr=False)
    impacts: Columns = field(repr=False)
    energy: Columns = field(repr=False)
    contacts: Columns = field(default_factory=dict, repr=False)
    """contacts.csv: each granule-hammer contact from start to end (empty: not recorded)."""
    label: str = ""
    """The run's name in analyses and reports; empty: its directory's name."""

    @property
    def name(self) -> str:
        """The run's label, or its directory's name."""
        return self.label or self.directory.name

    @property
    def omega(self) -> float:
        """Rotor angular velocity of the case, rad/s."""
        return self.case.rotor.angular_velocity

    def dataframe(self, table: str) -> Any:
        """Table ``table`` (one of :data:`TABLES`) as a pandas DataFrame, one
        column per CSV column (SI units); needs pandas (``pip install 'perga[notebook]'``)."""
        try:
            import pandas as pd
        except ImportError:
            raise ImportError(
                "Run.dataframe needs pandas (pip install 'perga[notebook]'); without it the "
                f"tables are numpy columns: run.{table}['time'], ..."
            ) from None
        if table not in TABLES:
            raise ValueError(f"no table {table!r}: {', '.join(TABLES[:-1])} or {TABLES[-1]}")
        return pd.DataFrame(getattr(self, table))

    def track(self, granule: int = 0) -> Columns:
        """One granule's rows of granules.csv: time (s), x, y (m), vx, vy (m/s), speed, ..."""
        rows = self.granules["id"] == granule
        return {k: v[rows] for k, v in self.granules.items()}

    def rotor_angle(self, t: FloatArray | float) -> FloatArray:
        """Rotor angle (rad) at times t (s), interpolated in hammers.csv (row id = -1), or ωt
        for a run without that table (kinematic rotor)."""
        t = np.asarray(t, dtype=float)
        if not self.hammers or not self.hammers["id"].size:
            return self.omega * t
        rows = self.hammers["id"] == -1
        return np.interp(t, self.hammers["time"][rows], self.hammers["swing_angle"][rows])


def _optional(directory: Path, name: str) -> Columns:
    return {} if table_path(directory, name) is None else read_run_table(directory, name)


def load_run(directory: Path | str, label: str = "") -> Run:
    """Load a run directory written by ``perga run`` (case.toml and summary.json required);
    ``label``: its name in analyses and reports (default: the directory's)."""
    directory = Path(directory)
    for needed in ("case.toml", "summary.json"):
        if not (directory / needed).exists():
            raise FileNotFoundError(f"{directory} is not a run directory: no {needed}")
    summary = json.loads((directory / "summary.json").read_text(encoding="utf-8"))
    # the case file, named from the run directory (older runs: absolute); a run with its
    # geometry files copied into it (perga.run.directory) finds them there
    own = (directory / "geometry").is_dir()
    origin = (directory / summary["case"]).parent if summary.get("case") and not own else None
    return Run(
        directory=directory,
        case=load_case(directory / "case.toml", origin if origin and origin.is_dir() else None),
        summary=summary,
        granules=_optional(directory, "granules"),
        hammers=_optional(directory, "hammers"),
        impacts=_optional(directory, "impacts"),
        energy=_optional(directory, "energy"),
        contacts=_optional(directory, "contacts"),
        label=label,
    )


def hammer_mount_angle(case: Case, hammer: int) -> float:
    """Angle of a hammer's hinge on the rotor at rotor angle 0, rad (evenly spaced default)."""
    h = case.hammers
    return h.angles[hammer] if h.angles else 2 * math.pi * hammer / h.count
