"""Convex decomposition of a simple polygon for Pymunk: ear-clipping triangulation, then
Hertel–Mehlhorn merging of triangles across diagonals while the union stays convex (at most
four times the minimum number of pieces).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from perga.geometry.polygon import FloatArray, clean, counter_clockwise, cross, is_convex, size


def _inside_triangle(p: FloatArray, a: FloatArray, b: FloatArray, c: FloatArray) -> bool:
    """True if p is inside or on the counter-clockwise triangle a b c."""
    return cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0


def triangulate(polygon: ArrayLike) -> list[tuple[int, int, int]]:
    """Ear-clipping triangulation of a simple polygon: counter-clockwise vertex-index triples
    into the counter-clockwise version of ``polygon``. O(n³), fine for outlines of hundreds of
    vertices."""
    p = counter_clockwise(polygon)
    tol = 1e-14 * size(p) ** 2
    remaining = list(range(len(p)))
    triangles: list[tuple[int, int, int]] = []
    while len(remaining) > 3:
        m = len(remaining)
        for k in range(m):
            i, j, q_ = remaining[k - 1], remaining[k], remaining[(k + 1) % m]
            if cross(p[i], p[j], p[q_]) <= tol:
                continue  # reflex or flat corner: not an ear
            if any(
                _inside_triangle(p[q], p[i], p[j], p[q_])
                for q in remaining
                if q not in (i, j, q_)
                and not np.array_equal(p[q], p[i])
                and not np.array_equal(p[q], p[q_])
            ):
                continue
            triangles.append((i, j, q_))
            del remaining[k]
            break
        else:
            raise ValueError("ear clipping found no ear: the polygon is not simple")
    triangles.append((remaining[0], remaining[1], remaining[2]))
    return triangles


def _merge(a: list[int], b: list[int], i: int, j: int) -> list[int]:
    """Union of pieces a (with edge i→j) and b (with edge j→i) across that diagonal."""
    ka = a.index(j)
    a_from_j = a[ka:] + a[:ka]  # j ... i
    kb = b.index(i)
    b_from_i = b[kb:] + b[:kb]  # i ... j
    return a_from_j + b_from_i[1:-1]


def decompose(polygon: ArrayLike) -> list[FloatArray]:
    """Convex pieces (counter-clockwise (n, 2) arrays) whose union is the simple ``polygon``;
    a convex polygon comes back whole (counter-clockwise, collinear vertices dropped)."""
    p = clean(counter_clockwise(polygon))
    if is_convex(p):
        return [p]
    pieces: list[list[int] | None] = [list(t) for t in triangulate(p)]
    merged = True
    while merged:
        merged = False
        owner: dict[tuple[int, int], int] = {}
        for n, piece in enumerate(pieces):
            if piece is not None:
                for k, v in enumerate(piece):
                    owner[(v, piece[(k + 1) % len(piece)])] = n
        for (i, j), n in owner.items():
            m = owner.get((j, i))
            if m is None or m == n or pieces[n] is None or pieces[m] is None:
                continue
            candidate = _merge(pieces[n], pieces[m], i, j)  # type: ignore[arg-type]
            if is_convex(p[candidate]):
                pieces[n], pieces[m] = candidate, None
                merged = True
                break
    return [clean(p[piece]) for piece in pieces if piece is not None]
