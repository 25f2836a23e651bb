"""Where a disc may be put: clear of other discs, of solid polygons (hammers) and inside a
container (the chamber), SI units.

Discs against discs use a k-d tree (``scipy.spatial.cKDTree``): O(n log n), never all pairs.
Discs against polygons and the container are vectorised over the discs, with a bounding-circle
cull per polygon and, for the container, its inscribed circle about the origin (discs within
it are inside). ``allowed`` is an overlap accepted with the polygons and the container (a
granule resting on a floor sits at its static overlap), m.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


CHUNK = 2048
"""Points handled at a time against a polygon's edges (bounds the work arrays)."""


def _segment_distance(points: FloatArray, polygon: FloatArray) -> FloatArray:
    """Distance from each point to the polygon's boundary, (n,)."""
    if len(points) > CHUNK:
        return np.concatenate(
            [
                _segment_distance(points[k : k + CHUNK], polygon)
                for k in range(0, len(points), CHUNK)
            ]
        )
    a = polygon
    b = np.roll(polygon, -1, axis=0)
    e = b - a
    ee = np.einsum("ij,ij->i", e, e)
    d = points[:, None, :] - a[None, :, :]
    t = np.clip(np.einsum("nij,ij->ni", d, e) / ee, 0.0, 1.0)
    closest = a[None, :, :] + t[..., None] * e[None, :, :]
    return np.min(np.linalg.norm(points[:, None, :] - closest, axis=2), axis=1)


def inside(points: FloatArray, polygon: FloatArray) -> BoolArray:
    """Whether each point is inside the simple polygon (even-odd rule), (n,)."""
    x, y = points[:, 0:1], points[:, 1:2]
    ax, ay = polygon[:, 0], polygon[:, 1]
    bx, by = np.roll(ax, -1), np.roll(ay, -1)
    crosses = (ay > y) != (by > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        xs = ax + (y - ay) * (bx - ax) / (by - ay)
    return np.count_nonzero(crosses & (x < xs), axis=1) % 2 == 1


@dataclass(frozen=True)
class Obstacles:
    """Solid polygons (world outlines, m) and the container a disc must stay in: an inner
    outline (m), or a circle of ``container_radius`` about the origin, or neither."""

    polygons: Sequence[FloatArray] = ()
    container: FloatArray | None = None
    container_radius: float | None = None
    _bounds: list[tuple[FloatArray, float]] = field(default_factory=list, repr=False)
    _inscribed: list[float] = field(default_factory=list, repr=False)

    def __post_init__(self) -> None:
        for p in self.polygons:
            centre = p.mean(axis=0)
            self._bounds.append((centre, float(np.max(np.linalg.norm(p - centre, axis=1)))))
        if self.container is not None:
            origin = np.zeros((1, 2))
            within = bool(inside(origin, self.container)[0])
            nearest = float(_segment_distance(origin, self.container)[0]) if within else 0.0
            self._inscribed.append(nearest * (1 - 1e-9))

    def clear(self, points: ArrayLike, radii: ArrayLike, allowed: float = 0.0) -> BoolArray:
        """Whether each disc (centre, radius) is clear of every polygon and inside the
        container, an overlap of ``allowed`` (m) accepted."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        r = np.asarray(radii, dtype=float).reshape(-1)
        ok = np.ones(len(p), dtype=bool)
        for polygon, (centre, reach) in zip(self.polygons, self._bounds, strict=True):
            near = np.linalg.norm(p - centre, axis=1) < reach + r
            if near.any():
                q = p[near]
                hit = inside(q, polygon) | (_segment_distance(q, polygon) < r[near] - allowed)
                ok[np.flatnonzero(near)[hit]] = False
        if self.container is not None:
            edge = np.linalg.norm(p, axis=1) + r > self._inscribed[0]  # else deep inside
            q = p[edge]
            ok[edge] &= inside(q, self.container)
            ok[edge] &= _segment_distance(q, self.container) >= r[edge] - allowed
        if self.container_radius is not None:
            ok &= np.linalg.norm(p, axis=1) <= self.container_radius - r + allowed
        return ok


def overlapping_pairs(points: ArrayLike, radii: ArrayLike) -> NDArray[np.int64]:
    """The pairs (i < j) of discs that overlap, (k, 2), from a k-d tree."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    r = np.asarray(radii, dtype=float).reshape(-1)
    if len(p) < 2:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = cKDTree(p).query_pairs(2.0 * float(r.max()), output_type="ndarray")
    if len(pairs) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    gap = np.linalg.norm(p[pairs[:, 0]] - p[pairs[:, 1]], axis=1)
    return pairs[gap < r[pairs[:, 0]] + r[pairs[:, 1]]].astype(np.int64)


def clear_of(
    points: ArrayLike, radii: ArrayLike, others: ArrayLike, other_radii: ArrayLike
) -> BoolArray:
    """Whether each disc overlaps none of the ``others`` (a k-d tree over them)."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    r = np.asarray(radii, dtype=float).reshape(-1)
    q = np.asarray(others, dtype=float).reshape(-1, 2)
    s = np.asarray(other_radii, dtype=float).reshape(-1)
    ok = np.ones(len(p), dtype=bool)
    if len(q) == 0 or len(p) == 0:
        return ok
    tree = cKDTree(q)
    reach = r + float(s.max())
    for i, near in enumerate(tree.query_ball_point(p, reach)):
        if near:
            ok[i] = bool(np.all(np.linalg.norm(q[near] - p[i], axis=1) >= r[i] + s[near]))
    return ok
