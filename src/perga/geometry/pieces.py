"""Which features of a body's convex pieces are its outline: solid edges, owned corners and
shallow concave joints (the arrays :mod:`perga.geometry.disc_polygon` reads)."""

import math

import numpy as np

from perga.geometry.disc_polygon import CORNER, SMOOTH_JOINT

SMOOTH_TURN = math.radians(15.0)
"""Concave joints turning by less than this (rad) split their faces' contacts at the bisector;
sharper ones (a 90° notch) keep a contact per face the disc touches."""


def whole_features(polygons: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(solid, corner) of polygons that are each a whole convex body
    (:mod:`perga.geometry.disc_polygon`)."""
    solid, corner, offset = [], [], 0
    for p in polygons:
        m = len(p)
        local = np.arange(m)
        solid.append(np.ones(m, dtype=np.int8))
        ends = offset + np.stack([(local - 1) % m, (local + 1) % m], axis=1)
        corner.append(np.column_stack([ends, np.full(m, CORNER)]))
        offset += m
    return np.concatenate(solid), np.concatenate(corner).astype(np.int64)


def piece_features(
    pieces: list[np.ndarray], loops: list[np.ndarray], rel_tol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray]:
    """(solid, corner) of the convex ``pieces`` of one body whose outline is ``loops`` (each
    (n, 2), walked with the body on its left: the outer loop counter-clockwise, holes
    clockwise), vertex indices counted over the pieces concatenated
    (:mod:`perga.geometry.disc_polygon`).

    An edge is solid when its midpoint lies on a loop; a loop vertex where the body is convex
    (turning left) is owned by the first piece that has it; one turning right by less than
    ``SMOOTH_TURN`` is a smooth joint in every piece that has it. Lengths in any unit;
    ``rel_tol`` is relative to the body's size.
    """
    flat = np.concatenate(pieces)
    tol = rel_tol * float(np.ptp(np.concatenate(loops), axis=0).max())
    segments = np.concatenate([np.stack([q, np.roll(q, -1, axis=0)], axis=1) for q in loops])

    def index_of(point: np.ndarray) -> int:
        return int(np.argmin(np.hypot(*(flat - point).T)))

    def copies(point: np.ndarray) -> np.ndarray:
        return np.nonzero(np.hypot(*(flat - point).T) <= tol)[0]

    def on_loop(point: np.ndarray) -> bool:
        a, b = segments[:, 0], segments[:, 1]
        e = b - a
        t = np.clip(np.einsum("ij,ij->i", point - a, e) / np.einsum("ij,ij->i", e, e), 0, 1)
        return bool(np.min(np.hypot(*(a + t[:, None] * e - point).T)) <= tol)

    edges = [zip(p, np.roll(p, -1, axis=0), strict=True) for p in pieces]
    solid = np.array([on_loop(0.5 * (v + w)) for e in edges for v, w in e], dtype=np.int8)
    corner = np.tile(np.array([-1, -1, 0], dtype=np.int64), (len(flat), 1))
    for loop in loops:
        turns = zip(np.roll(loop, 1, axis=0), loop, np.roll(loop, -1, axis=0), strict=True)
        for before, vertex, after in turns:
            (ax, ay), (bx, by) = vertex - before, after - vertex
            angle = math.atan2(ax * by - ay * bx, ax * bx + ay * by)  # > 0: convex
            ends = (index_of(before), index_of(after))
            at = copies(vertex)
            if angle > 0 and len(at):
                corner[at[0]] = (*ends, CORNER)
            elif -SMOOTH_TURN < angle <= 0:
                corner[at] = (*ends, SMOOTH_JOINT)
    return solid, corner


def outline_arrays(
    pieces: list[np.ndarray], loops: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, start, solid, corner) of the convex ``pieces`` of one body whose outline is
    ``loops`` (:func:`piece_features`): what :func:`perga.geometry.disc_polygon.closest_feature`
    takes after the point; piece k owns ``vertices[start[k]:start[k + 1]]``."""
    polygons = [np.ascontiguousarray(p, dtype=np.float64) for p in pieces]
    start = np.zeros(len(polygons) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(p) for p in polygons])
    solid, corner = piece_features(polygons, loops)
    return (
        np.ascontiguousarray(np.concatenate(polygons)),
        start,
        np.ascontiguousarray(solid, dtype=np.int8),
        np.ascontiguousarray(corner, dtype=np.int64),
    )
