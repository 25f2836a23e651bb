"""Mass properties of a planar part: the MassProperties record, and the exact polygon formulas
for an outline (with holes) extruded to a thickness.

The rotor plane is the xy plane; moments are about axes along z (normal to the plane).
Units: m, kg, kg/m³, kg·m².
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perga.geometry.polygon import as_points

Vec2 = tuple[float, float]


@dataclass(frozen=True)
class MassProperties:
    """A part's mass, kg; in-plane centre of mass, m; and I_z about the axis through the centre
    of mass normal to the rotor plane, kg·m²."""

    mass: float
    centre_of_mass: Vec2
    moment_about_centre: float

    def moment_about(self, point: ArrayLike) -> float:
        """I_z about the axis normal to the plane through ``point`` (m), kg·m² (parallel axes)."""
        px, py = (float(c) for c in np.asarray(point, dtype=float))
        cx, cy = self.centre_of_mass
        return self.moment_about_centre + self.mass * ((cx - px) ** 2 + (cy - py) ** 2)


@dataclass(frozen=True)
class AreaProperties:
    """Area, m²; centroid, m; polar second moment of area about the centroid, m⁴."""

    area: float
    centroid: Vec2
    polar_moment_about_centroid: float


def _raw_moments(points: ArrayLike) -> tuple[float, float, float, float]:
    """Signed area, first moments (∫x, ∫y) and polar moment ∫(x²+y²) about the origin."""
    p = as_points(points)
    x0, y0 = p[:, 0], p[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    c = x0 * y1 - x1 * y0
    area = 0.5 * float(np.sum(c))
    sx = float(np.sum((x0 + x1) * c)) / 6
    sy = float(np.sum((y0 + y1) * c)) / 6
    j = float(np.sum(c * (x0 * x0 + x0 * x1 + x1 * x1 + y0 * y0 + y0 * y1 + y1 * y1))) / 12
    return area, sx, sy, j


def area_properties(outline: ArrayLike, holes: Sequence[ArrayLike] = ()) -> AreaProperties:
    """Area properties of a polygon (either winding) minus its holes (m)."""
    totals = np.zeros(4)
    for k, loop in enumerate([outline, *holes]):
        raw = np.array(_raw_moments(loop))
        sign = math.copysign(1.0, raw[0]) * (1.0 if k == 0 else -1.0)
        totals += sign * raw
    area, sx, sy, j = (float(t) for t in totals)
    if not area > 0:
        raise ValueError(f"the outline minus its holes has no area (got {area} m²)")
    cx, cy = sx / area, sy / area
    return AreaProperties(area, (cx, cy), j - area * (cx * cx + cy * cy))


def extruded_properties(
    outline: ArrayLike, thickness: float, density: float, holes: Sequence[ArrayLike] = ()
) -> MassProperties:
    """A polygon (m) minus holes, extruded to ``thickness`` (m) of ``density`` (kg/m³).

    M = ρtA, centre = centroid, I_z = ρt·J (J the polar moment of area about the centroid).
    """
    if not (math.isfinite(thickness) and thickness > 0):
        raise ValueError(f"thickness must be finite and > 0 m (got {thickness})")
    if not (math.isfinite(density) and density > 0):
        raise ValueError(f"density must be finite and > 0 kg/m³ (got {density})")
    props = area_properties(outline, holes)
    per_area = density * thickness
    return MassProperties(
        per_area * props.area, props.centroid, per_area * props.polar_moment_about_centroid
    )
