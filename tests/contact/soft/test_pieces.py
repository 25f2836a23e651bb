"""A body of several convex pieces (an L-shaped plate split by the decomposition) against
discs: only its outline makes contacts (``perga.geometry.pieces.piece_features``).

References: a convex square with the same corner, hit the same way, gives the same forces at
the same times, so the two runs agree to round-off (1e-12 relative asserted; the arithmetic
differs only in the order of the broad phase); a disc driven along the bisector into the
L's 90° notch touches both faces at once, two independent frictionless normal contacts on an
immovable body, so it leaves along the bisector at e v0 (0.5 % at t_c/50, the soft-contact
restitution tolerance of tests/soft).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from perga.contact.soft.polygon_set import HIST_ACTIVE, KINEMATIC, polygon_set
from perga.geometry.convex import decompose
from perga.geometry.pieces import piece_features

from .test_kernel_polygons import _granules, _linear
from .test_polygons import R

SIDE = 0.02  # m
L_SHAPE = SIDE * np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
NOTCH = SIDE * np.array([1.0, 1.0])


def _l_pieces():
    pieces = decompose(L_SHAPE)
    features = piece_features(pieces, [L_SHAPE])
    return pieces, polygon_set(
        pieces, np.zeros((len(pieces), 2)), kind=[KINEMATIC] * len(pieces), features=features
    )


def _split_corner(pieces) -> np.ndarray:
    """The convex corner of the L that two pieces share (the far end of the diagonal)."""
    shared = [v for v in L_SHAPE if sum(np.any(np.all(p == v, axis=1)) for p in pieces) == 2]
    return next(v for v in shared if not np.allclose(v, NOTCH))


def _fire(polys, start, velocity, e=0.7, friction=0.3):
    table, dt = _linear(e, friction=friction)
    g = _granules([start], [velocity], polys, table, dt)
    touched = False
    for _ in range(20_000):
        g.step(5)
        active = bool(np.any(g.polygon_hist[0, :, HIST_ACTIVE] != 0.0))
        touched |= active
        if touched and not active:
            return g
    raise AssertionError("the disc did not leave the body")


def test_pieces_features():
    """Two pieces; the diagonal between them is not solid; the L's five convex corners are each
    owned once, the notch corner by nobody."""
    pieces, polys = _l_pieces()
    assert len(pieces) == 2
    assert int(np.sum(polys.solid == 0)) == 2  # the diagonal, once in each piece
    owned = polys.vertices[polys.corner[:, 0] >= 0]
    assert len(owned) == 5
    assert not np.any(np.all(np.isclose(owned, NOTCH), axis=1))


@pytest.mark.parametrize("direction_deg", [225.0, 200.0, 250.0, 160.0, 290.0])
def test_split_corner_hits_like_a_convex_corner(direction_deg):
    """A disc fired at the corner the diagonal splits, from inside the corner's region
    (200–250°: both pieces overlap the disc, and counting both changes the rebound by 10 %,
    measured), or at a face just beside the corner (160°, 290°: the face contact must not be
    lost to the corner rule): the same as the square with that corner and faces."""
    pieces, polys = _l_pieces()
    corner = _split_corner(pieces)
    away = np.array([math.cos(math.radians(direction_deg)), math.sin(math.radians(direction_deg))])
    start = corner + away * (R + 1e-4)
    velocity = -2.0 * away + 0.3 * np.array([-away[1], away[0]])
    square = SIDE * np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    # the square with the L's corner and both its edges there
    inward = L_SHAPE.mean(axis=0) - corner
    square = corner + (square - square.mean(axis=0) + SIDE / 2) * np.sign(inward)
    square = square if _area(square) > 0 else square[::-1]
    whole = polygon_set([square], np.zeros((1, 2)), kind=[KINEMATIC])
    got = _fire(polys, start, velocity)
    want = _fire(whole, start, velocity)
    assert np.allclose(got.v, want.v, rtol=1e-12, atol=1e-12 * 2.0)
    assert np.allclose(got.w, want.w, rtol=1e-12, atol=1e-9)
    assert np.linalg.norm(want.v[0] - velocity) > 0.5  # it did bounce


def _area(p):
    x, y = p[:, 0], p[:, 1]
    return 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)


@pytest.mark.parametrize("e", [0.5, 0.7, 0.9])
def test_notch_gives_two_contacts_and_restitutes_along_the_bisector(e):
    _, polys = _l_pieces()
    out = np.array([1.0, 1.0]) / math.sqrt(2.0)
    v0 = 2.0
    g = _fire(polys, NOTCH + out * (R * math.sqrt(2.0) + 1e-4), -v0 * out, e=e, friction=0.0)
    assert g.v[0] @ out == pytest.approx(e * v0, rel=5e-3)
    assert abs(g.v[0] @ np.array([-out[1], out[0]])) <= 1e-9 * v0
