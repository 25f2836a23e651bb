"""Length units a geometry file may be declared in, and the geometry error type."""

from __future__ import annotations

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
