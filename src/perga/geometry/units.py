"""Length units a geometry file may be declared in, the extent its coordinates may have, and the
geometry error type."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

UNIT_SCALE: dict[str, float] = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "in": 0.0254}
"""Metres per file unit."""


class GeometryError(ValueError):
    """Bad geometry: the message names the file (or part) and the problem."""


def unit_scale(units: str, source: str = "geometry") -> float:
    """Metres per ``units`` (one of UNIT_SCALE); GeometryError naming ``source`` otherwise."""
    try:
        return UNIT_SCALE[units]
    except KeyError:
        raise GeometryError(
            f"{source}: unknown units {units!r} (use one of {', '.join(UNIT_SCALE)})"
        ) from None


FARTHEST = 10.0
"""Largest |coordinate| of a part drawn in a geometry file, m (after scaling): a scene lies
within 5 m of the rotor axis (a case file's largest radius), so a part within 10 m of its
hinge; larger numbers are a wrong unit, and far larger ones overflow the geometry's squares."""


def check_extent(points: ArrayLike, source: str) -> None:
    """GeometryError naming ``source`` unless every coordinate of ``points`` (m) is finite and
    within ±``FARTHEST``."""
    values = np.asarray(points, dtype=float).ravel()
    outside = values[~(np.abs(values) <= FARTHEST)]
    if len(outside):
        raise GeometryError(
            f"{source}: coordinates must be finite and within ±{FARTHEST:g} m after scaling "
            f"to metres (got {float(outside[0])} m; is the unit right?)"
        )
