"""Units of a data file's columns: a column may carry its unit in brackets after its name,
``granules.placement.angle [deg]``, ``first_impact_rebound_angle_centre_sd [deg]``; its values
are converted to SI, which the case and the metrics use. A column without brackets is SI."""

from __future__ import annotations

import math
import re

UNITS: dict[str, tuple[str, float]] = {
    "-": ("dimensionless", 1.0),
    "1": ("dimensionless", 1.0),
    "%": ("dimensionless", 0.01),
    "rad": ("angle", 1.0),
    "deg": ("angle", math.pi / 180),
    "m": ("length", 1.0),
    "cm": ("length", 1e-2),
    "mm": ("length", 1e-3),
    "um": ("length", 1e-6),
    "s": ("time", 1.0),
    "ms": ("time", 1e-3),
    "m/s": ("speed", 1.0),
    "mm/s": ("speed", 1e-3),
    "cm/s": ("speed", 1e-2),
    "rad/s": ("angular velocity", 1.0),
    "rpm": ("angular velocity", 2 * math.pi / 60),
    "deg/s": ("angular velocity", math.pi / 180),
    "kg": ("mass", 1.0),
    "g": ("mass", 1e-3),
    "mg": ("mass", 1e-6),
    "J": ("energy", 1.0),
    "mJ": ("energy", 1e-3),
    "J/kg": ("specific energy", 1.0),
    "kg/s": ("mass flow", 1.0),
    "g/s": ("mass flow", 1e-3),
}
"""Unit -> (dimension, factor to SI)."""

_BRACKETS = re.compile(r"^(?P<name>[^\[\]]*?)\s*\[(?P<unit>[^\[\]]*)\]\s*$")


def split_unit(column: str) -> tuple[str, str | None]:
    """``NAME [UNIT]`` -> (NAME, UNIT); a column without brackets -> (column, None)."""
    match = _BRACKETS.match(column)
    if match is None:
        return column.strip(), None
    return match["name"], match["unit"].strip()


def to_si(unit: str | None, si_unit: str | None = None) -> float:
    """The factor that takes values in ``unit`` to SI (1 for None); ValueError for a unit not
    in :data:`UNITS` or, given the quantity's ``si_unit``, of another dimension."""
    if unit is None:
        return 1.0
    if unit not in UNITS:
        raise ValueError(f"unknown unit [{unit}]; units: {', '.join(UNITS)}")
    dimension, factor = UNITS[unit]
    if si_unit is not None and si_unit in UNITS and UNITS[si_unit][0] != dimension:
        raise ValueError(
            f"[{unit}] is a unit of {dimension}; this column is in {UNITS[si_unit][0]} "
            f"([{si_unit}] in SI)"
        )
    return factor
