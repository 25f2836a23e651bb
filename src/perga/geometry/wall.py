"""A chamber wall of uniform thickness around a closed inner outline, as convex pieces.

Each edge of the inner outline gets one quadrilateral: the edge, and the same edge offset
outwards by ``thickness``, joined to its neighbours along the mitre lines (bisectors) of its two
vertices. Neighbouring pieces share their mitre side exactly: no gaps, no overlaps; the outer
outline is the inner one offset by ``thickness``. At a sharp convex corner of the wall (where
an outlet channel leaves a round chamber) the mitre shortens the offset edges, so a short edge
there limits the thickness (``wall_pieces`` says so). Thick walls stop fast granules tunnelling
(docs/pymunk.md); a round chamber is the circumscribed N-gon of its circle.

Units: those of the input (m in perga).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from perga.geometry.polygon import (
    FloatArray,
    clean,
    contains,
    counter_clockwise,
    is_convex,
    signed_area,
)
from perga.geometry.units import GeometryError


def circumscribed(radius: float, sides: int) -> FloatArray:
    """The regular ``sides``-gon whose edges touch the circle of ``radius`` (counter-clockwise,
    vertices at the angles (2i + 1)π/sides), m: at most radius·(1/cos(π/sides) − 1) outside the
    circle. With ``sides`` a multiple of 4 an edge's middle, not a corner, lies on each axis,
    −y included: a granule dropped under the axis of a vertical rotor lands on a flat edge, as
    on the circle's lowest point (a corner there turned it aside by up to 2π/sides)."""
    angles = (2 * np.arange(sides) + 1) * math.pi / sides
    return radius / math.cos(math.pi / sides) * np.c_[np.cos(angles), np.sin(angles)]


def _mitres(inner: FloatArray) -> FloatArray:
    """Offset of each vertex of a counter-clockwise outline that moves both its edges outwards
    (to their right) by 1: (n_before + n_after)/(1 + n_before·n_after)."""
    edges = np.roll(inner, -1, axis=0) - inner
    after = np.c_[edges[:, 1], -edges[:, 0]] / np.hypot(*edges.T)[:, None]
    before = np.roll(after, 1, axis=0)
    return (before + after) / (1.0 + np.einsum("ij,ij->i", before, after))[:, None]


def wall_pieces(
    inner: ArrayLike, thickness: float, source: str = "chamber"
) -> tuple[list[FloatArray], FloatArray]:
    """The wall's convex pieces (counter-clockwise quadrilaterals, one per inner edge) and its
    outer outline (counter-clockwise). Raises GeometryError naming ``source`` when a piece
    folds over (an edge shorter than the thickness at a sharp inward corner) or reaches into
    the chamber (a passage narrower than the thickness)."""
    if not (math.isfinite(thickness) and thickness > 0):
        raise GeometryError(f"{source}: wall thickness must be > 0 (got {thickness})")
    p = clean(counter_clockwise(inner))
    outer = p + thickness * _mitres(p)
    pieces = []
    for i in range(len(p)):
        j = (i + 1) % len(p)
        quad = counter_clockwise(np.array([p[i], outer[i], outer[j], p[j]]))
        if not is_convex(quad) or signed_area(quad) <= 0.0:
            raise GeometryError(
                f"{source}: the wall piece on edge {i} folds over: the edge is too short for "
                f"a wall {thickness:g} m thick at its corners; use a thinner wall"
            )
        pieces.append(quad)
    for k, point in enumerate(outer):
        if contains(p, point):
            raise GeometryError(
                f"{source}: the wall {thickness:g} m thick reaches into the chamber at vertex "
                f"{k}; use a thinner wall"
            )
    return pieces, outer
