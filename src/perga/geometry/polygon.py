"""Plain 2-D polygon helpers: area, orientation, cleanup, convexity, self-intersection and
point-in-polygon. A polygon is an (n, 2) array of vertices without the closing repeat.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def as_points(points: ArrayLike) -> FloatArray:
    """The vertices as a float (n, 2) array."""
    array = np.asarray(points, dtype=float)
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"a polygon needs (n, 2) vertices (got shape {array.shape})")
    return array


def outline_or_circle(
    outline: ArrayLike | None, radius: float, sides: int, angle: float = 0.0
) -> FloatArray:
    """``outline`` as an (n, 2) array, or without one the regular ``sides``-gon inscribed in
    the circle of ``radius`` about the origin, counter-clockwise from ``angle`` (rad)."""
    if outline is not None:
        return as_points(outline)
    phi = angle + 2.0 * np.pi * np.arange(sides) / sides
    return radius * np.column_stack((np.cos(phi), np.sin(phi)))


def vertex_tuples(points: ArrayLike) -> tuple[tuple[float, float], ...]:
    """The vertices as a tuple of (x, y) float pairs (hashable, for frozen specs)."""
    return tuple((float(x), float(y)) for x, y in as_points(points))


def signed_area(points: ArrayLike) -> float:
    """Shoelace area, m² (> 0 counter-clockwise)."""
    p = as_points(points)
    q = np.roll(p, -1, axis=0)
    return float(0.5 * np.sum(p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]))


def counter_clockwise(points: ArrayLike) -> FloatArray:
    """The polygon with counter-clockwise winding (reversed if it was clockwise)."""
    p = as_points(points)
    return p if signed_area(p) >= 0 else p[::-1].copy()


def cross(o: FloatArray, a: FloatArray, b: FloatArray) -> float:
    """z of (a − o) × (b − o); > 0 when o → a → b turns left."""
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def size(points: ArrayLike) -> float:
    """Diagonal of the bounding box, m (the scale for relative tolerances)."""
    p = as_points(points)
    return float(np.hypot(*(p.max(axis=0) - p.min(axis=0)))) if len(p) else 0.0


def clean(points: ArrayLike, rel_tol: float = 1e-9) -> FloatArray:
    """Merge consecutive vertices closer than rel_tol·size (including a closing repeat of the
    first vertex) and drop vertices collinear with their neighbours (deviation below
    rel_tol·size)."""
    p = as_points(points)
    tol = rel_tol * max(size(p), np.finfo(float).tiny)
    kept: list[FloatArray] = []
    for v in p:
        if not kept or np.hypot(*(v - kept[-1])) > tol:
            kept.append(v)
    while len(kept) > 1 and np.hypot(*(kept[0] - kept[-1])) <= tol:
        kept.pop()
    changed = True
    while changed and len(kept) >= 3:
        changed = False
        for i in range(len(kept)):
            a, b, c = kept[i - 1], kept[i], kept[(i + 1) % len(kept)]
            base = float(np.hypot(*(c - a)))
            if base <= tol:
                continue  # a spike going back on itself: the self-intersection check reports it
            along = float(np.dot(b - a, c - a)) / base**2
            if abs(cross(a, b, c)) / base <= tol and 0.0 <= along <= 1.0:
                del kept[i]  # b sits on the segment a-c
                changed = True
                break
    return np.array(kept, dtype=float).reshape(-1, 2)


def is_convex(points: ArrayLike, rel_tol: float = 1e-12) -> bool:
    """True for a convex polygon wound counter-clockwise (collinear vertices allowed)."""
    p = as_points(points)
    tol = rel_tol * size(p) ** 2
    n = len(p)
    turns = [cross(p[i - 1], p[i], p[(i + 1) % n]) for i in range(n)]
    angles = [
        np.arctan2(t, np.dot(p[i] - p[i - 1], p[(i + 1) % n] - p[i])) for i, t in enumerate(turns)
    ]
    return n >= 3 and min(turns) >= -tol and abs(sum(angles) - 2 * np.pi) < 1e-6


def _segments_cross(a: FloatArray, b: FloatArray, c: FloatArray, d: FloatArray) -> bool:
    """True if closed segments a-b and c-d share a point."""
    d1, d2 = cross(c, d, a), cross(c, d, b)
    d3, d4 = cross(a, b, c), cross(a, b, d)
    if ((d1 > 0 > d2) or (d1 < 0 < d2)) and ((d3 > 0 > d4) or (d3 < 0 < d4)):
        return True

    def on(p: FloatArray, q: FloatArray, r: FloatArray, turn: float) -> bool:
        return (
            turn == 0
            and min(p[0], q[0]) <= r[0] <= max(p[0], q[0])
            and min(p[1], q[1]) <= r[1] <= max(p[1], q[1])
        )

    return on(c, d, a, d1) or on(c, d, b, d2) or on(a, b, c, d3) or on(a, b, d, d4)


def self_intersection(points: ArrayLike) -> tuple[int, int] | None:
    """The first pair of edges (i, j), edge k running from vertex k to k+1, that touch or cross
    although they are not neighbours; None for a simple polygon."""
    p = as_points(points)
    n = len(p)
    for i in range(n):
        a, b = p[i], p[(i + 1) % n]
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                # neighbours share a vertex; they only overlap if they fold back on each other
                shared, other_i, other_j = (b, a, p[(j + 1) % n]) if j == i + 1 else (a, b, p[j])
                if cross(shared, other_i, other_j) == 0 and (
                    np.dot(other_i - shared, other_j - shared) > 0
                ):
                    return i, j
                continue
            if _segments_cross(a, b, p[j], p[(j + 1) % n]):
                return i, j
    return None


def contains(points: ArrayLike, point: ArrayLike) -> bool:
    """True if ``point`` lies strictly inside the polygon (on the boundary counts as outside)."""
    p = as_points(points)
    x, y = (float(c) for c in np.asarray(point, dtype=float))
    inside = False
    n = len(p)
    for i in range(n):
        (x0, y0), (x1, y1) = p[i], p[(i + 1) % n]
        if cross(p[i], p[(i + 1) % n], np.array([x, y])) == 0 and (
            min(x0, x1) <= x <= max(x0, x1) and min(y0, y1) <= y <= max(y0, y1)
        ):
            return False
        if (y0 > y) != (y1 > y) and x < x0 + (y - y0) * (x1 - x0) / (y1 - y0):
            inside = not inside
    return inside
