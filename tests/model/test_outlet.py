"""Where granules leave (``OutletSpec.leaving``): each limit from both sides, and the same
verdicts as the formula in numpy on random granules."""

import math

import numpy as np
import pytest

from perga.model.process import OutletSpec

R = 2e-3
SCREEN = OutletSpec("screen", point=(0.0, -0.38), normal=(0.0, -2.0), width=0.15, aperture=0.006)


@pytest.mark.parametrize(
    ("outlet", "position", "radius", "leaves"),
    [
        (OutletSpec("radius", radius=0.3), (0.3 - 1e-9, 0.0), R, False),
        (OutletSpec("radius", radius=0.3), (0.0, -0.3 - 1e-9), R, True),
        (OutletSpec("line", point=(0.0, -0.38), normal=(0.0, -1.0)), (5.0, -0.38 + R + 1e-9), R,
         False),
        (OutletSpec("line", point=(0.0, -0.38), normal=(0.0, -1.0)), (5.0, -0.38 + R - 1e-9), R,
         True),
        (SCREEN, (0.075 - 1e-9, -0.39), R, True),
        (SCREEN, (-0.075 - 1e-9, -0.39), R, False),
        (SCREEN, (0.0, -0.39), 0.003 - 1e-9, True),
        (SCREEN, (0.0, -0.39), 0.003, False),
        (SCREEN, (0.0, -0.38 + R - 1e-9), R, True),
        (SCREEN, (0.0, -0.38 + R + 1e-9), R, False),
    ],
)  # fmt: skip
def test_each_limit_from_both_sides(outlet, position, radius, leaves) -> None:
    """Beyond the radius; touching the line (centre within r of it, normal not unit); within
    half the screen's width along it; narrower than its aperture (2r < aperture)."""
    assert outlet.leaving(np.array([position]), np.array([radius])).tolist() == [leaves]


def test_the_verdicts_are_the_formula_in_numpy() -> None:
    """20,000 random granules about a slanted screen, and a radius outlet: the verdicts equal
    the definition written with numpy (d·n > −r, |d·t| ≤ w/2, 2r < aperture; |x| > R)."""
    rng = np.random.default_rng(7)
    p = rng.uniform(-0.3, 0.3, (20_000, 2))
    r = rng.uniform(1e-3, 4e-3, 20_000)
    outlet = OutletSpec("screen", point=(0.05, -0.1), normal=(1.0, -2.0), width=0.2, aperture=6e-3)
    n = np.array(outlet.normal) / math.hypot(*outlet.normal)
    d = p - np.array(outlet.point)
    along = np.abs(d[:, 0] * -n[1] + d[:, 1] * n[0])
    expected = (d[:, 0] * n[0] + d[:, 1] * n[1] > -r) & (along <= 0.1) & (2.0 * r < 6e-3)
    got = outlet.leaving(p, r)
    assert 100 < expected.sum() < 19_000
    np.testing.assert_array_equal(got, expected)
    radius = OutletSpec("radius", radius=0.25)
    np.testing.assert_array_equal(radius.leaving(p, r), np.hypot(p[:, 0], p[:, 1]) > 0.25)
