"""Convex decomposition for Pymunk."""

from __future__ import annotations

import numpy as np
import pytest

from perga.geometry import decompose, triangulate
from perga.geometry.polygon import is_convex, signed_area


def star(n: int = 7, depth: float = 0.5) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    r = np.where(np.arange(2 * n) % 2 == 0, 1.0, depth)
    return np.c_[r * np.cos(t), r * np.sin(t)]


SHAPES = {
    "L": np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2.0]]),
    "stepped": np.array(
        [[-15, -25], [75, -25], [75, -35], [135, -35], [135, 35], [75, 35], [75, 25], [-15, 25.0]]
    )
    * 1e-3,
    "star": star(),
    "comb_clockwise": np.array([[0, 0], [0, 2], [1, 2], [1, 1], [2, 1], [2, 2], [3, 2], [3, 0.0]]),
}


@pytest.mark.parametrize("name", SHAPES)
def test_pieces_are_convex_ccw_and_cover_the_area(name):
    polygon = SHAPES[name]
    pieces = decompose(polygon)
    assert len(pieces) > 1
    for piece in pieces:
        assert is_convex(piece) and signed_area(piece) > 0
    total = sum(signed_area(p) for p in pieces)
    assert total == pytest.approx(abs(signed_area(polygon)), rel=1e-12)
    assert len(triangulate(polygon)) == len(polygon) - 2


def test_convex_input_returns_itself():
    t = np.linspace(0, 2 * np.pi, 9, endpoint=False)
    hexagon_cw = np.c_[np.cos(t), np.sin(t)][::-1]
    (piece,) = decompose(hexagon_cw)
    np.testing.assert_array_equal(piece, hexagon_cw[::-1])
