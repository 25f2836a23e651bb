"""The geometry of a disc against a body made of convex pieces, compiled (numba), SI units.

A body (a hammer, a chamber wall) is a list of convex pieces whose union is the body; only its
outline makes contacts. Per vertex of the pieces concatenated, two arrays say what of the outline
a piece carries (:mod:`perga.geometry.pieces` builds them):

* ``solid`` (n_vertices,) int8: 1 where the edge from this vertex to the next lies on the
  outline, 0 on a seam between two pieces (never a contact);
* ``corner`` (n_vertices, 3) int64: for a vertex on the outline, the indices of the outline's
  vertices before and after it and its kind: ``CORNER``, a convex corner this piece owns (a
  contact there counts while the disc centre is in the corner's region, between the normals of
  the outline's two edges there); ``SMOOTH_JOINT``, a concave joint turning by less than
  :data:`perga.geometry.pieces.SMOOTH_TURN` (a face's contact there counts only on the face's
  side of the joint's bisector); 0 otherwise; (−1, −1, 0) off the outline.

So a disc touching one face or corner of the outline has one contact whichever pieces it
overlaps, and a disc in a concave notch one per face it touches. The closest feature
(:func:`closest_feature`) is the contact's geometry for the soft kernel, for the rigid engine's
hammers of several pieces and for the contact counts of the output.
"""

import math

import numba as nb
import numpy as np

FASTMATH = {"nsz", "arcp", "contract", "afn", "reassoc"}
"""LLVM fast-math flags of perga's compiled kernels: all but ``nnan`` and ``ninf`` (an infinite
speed cap and NaN checks must keep their meaning); docs/dev/performance.md has the gain."""

CORNER, SMOOTH_JOINT = 1, 2
"""Kinds of outline vertices (``corner[:, 2]``, module doc)."""


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def separation(px, py, verts, lo, hi):
    """Largest signed distance of (px, py) from the lines of the convex polygon verts[lo:hi]'s
    edges, m: a lower bound of its distance from the polygon (whatever features count)."""
    s_max = -np.inf
    for q in range(lo, hi):
        qb = q + 1 if q + 1 < hi else lo
        ex = verts[qb, 0] - verts[q, 0]
        ey = verts[qb, 1] - verts[q, 1]
        s = ((px - verts[q, 0]) * ey - (py - verts[q, 1]) * ex) / math.sqrt(ex * ex + ey * ey)
        s_max = max(s_max, s)
    return s_max


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def _past_joint(px, py, verts, corner, q):
    """(p − V)·(u_in + u_out) at the joint V = verts[q] (unit directions of the outline's edges
    into and out of V): < 0 on the incoming edge's side of the joint's bisector, > 0 beyond."""
    vx = verts[q, 0]
    vy = verts[q, 1]
    ix = vx - verts[corner[q, 0], 0]
    iy = vy - verts[corner[q, 0], 1]
    ox = verts[corner[q, 1], 0] - vx
    oy = verts[corner[q, 1], 1] - vy
    l_in = math.sqrt(ix * ix + iy * iy)
    l_out = math.sqrt(ox * ox + oy * oy)
    return (px - vx) * (ix / l_in + ox / l_out) + (py - vy) * (iy / l_in + oy / l_out)


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def closest_feature(px, py, verts, start, solid, corner, k):
    """Signed distance d of (px, py) to convex piece k and the normal n, over the piece's solid
    features only (module doc). verts (n_vertices, 2): every piece's vertices, counter-clockwise,
    concatenated; start (n_pieces + 1,): piece k owns verts[start[k]:start[k + 1]]; solid,
    corner: the pieces' outline features (:mod:`perga.geometry.pieces`).

    Outside: d = distance to the closest point of a solid edge, n from that point to the centre;
    a closest point at a corner counts only if the polygon owns the corner and the centre lies
    in the corner's region of the whole outline, one inside an edge ending at a smooth joint
    only on the edge's side of the joint's bisector; else there is no contact (d = inf, n = 0).
    Inside: d = largest signed distance to a solid edge (≤ 0), n = that edge's outward normal.
    Returns (d, n_x, n_y), m and unit vector.
    """
    first = last = -1
    lo = start[k]
    m = start[k + 1] - lo
    s_all = -np.inf
    s_max = -np.inf
    nx_max = 0.0
    ny_max = 0.0
    for j in range(m):
        ax, ay = verts[lo + j, 0], verts[lo + j, 1]
        jb = lo + j + 1 if j + 1 < m else lo
        ex = verts[jb, 0] - ax
        ey = verts[jb, 1] - ay
        inv = 1.0 / math.sqrt(ex * ex + ey * ey)
        nx = ey * inv
        ny = -ex * inv
        s = (px - ax) * nx + (py - ay) * ny
        s_all = max(s_all, s)
        if solid[lo + j] != 0 and s > s_max:
            s_max = s
            nx_max = nx
            ny_max = ny
    if s_all <= 0.0:
        if s_max == -np.inf:  # a piece with no solid edge
            return np.inf, 0.0, 0.0
        return s_max, nx_max, ny_max
    # Outside: closest point over the solid edges (segments).
    d2_min = np.inf
    qx_min = 0.0
    qy_min = 0.0
    vertex = -1
    for j in range(m):
        if solid[lo + j] == 0:
            continue
        ax, ay = verts[lo + j, 0], verts[lo + j, 1]
        jb = lo + j + 1 if j + 1 < m else lo
        ex = verts[jb, 0] - ax
        ey = verts[jb, 1] - ay
        t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
        t = min(max(t, 0.0), 1.0)
        qx = ax + t * ex
        qy = ay + t * ey
        d2 = (px - qx) * (px - qx) + (py - qy) * (py - qy)
        if d2 < d2_min:
            d2_min = d2
            qx_min = qx
            qy_min = qy
            vertex = lo + j if t == 0.0 else (jb if t == 1.0 else -1)
            first, last = lo + j, jb
    if d2_min == np.inf:
        return np.inf, 0.0, 0.0
    if vertex >= 0:
        if corner[vertex, 2] != CORNER:
            return np.inf, 0.0, 0.0
        vx = verts[vertex, 0]
        vy = verts[vertex, 1]
        before, after = corner[vertex, 0], corner[vertex, 1]
        into = (px - vx) * (vx - verts[before, 0]) + (py - vy) * (vy - verts[before, 1])
        out = (px - vx) * (verts[after, 0] - vx) + (py - vy) * (verts[after, 1] - vy)
        if into < 0.0 or out > 0.0:
            return np.inf, 0.0, 0.0
    elif (corner[first, 2] == SMOOTH_JOINT and _past_joint(px, py, verts, corner, first) < 0.0) or (
        corner[last, 2] == SMOOTH_JOINT and _past_joint(px, py, verts, corner, last) > 0.0
    ):
        return np.inf, 0.0, 0.0
    d = math.sqrt(d2_min)
    return d, (px - qx_min) / d, (py - qy_min) / d


@nb.njit(cache=True)
def bounding_radii(verts, start, com):
    """Radius of each polygon's bounding circle about its centre of mass, (n_poly,), m."""
    n_poly = com.shape[0]
    rho = np.zeros(n_poly)
    for k in range(n_poly):
        for q in range(start[k], start[k + 1]):
            dx = verts[q, 0] - com[k, 0]
            dy = verts[q, 1] - com[k, 1]
            rho[k] = max(rho[k], math.sqrt(dx * dx + dy * dy))
    return rho
