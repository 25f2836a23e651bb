"""Frictionless bead on a radial blade of a rotor at constant ω (design §4 closed form)."""

from __future__ import annotations

import pytest

from perga.analytic.sliding import frictionless_exit
from tests.engine.helpers import blade_exit

OMEGA = 100.0  # rad/s
X0 = 0.05  # m, start radius
TIP = 0.15  # m, blade tip
RADIUS = 0.002  # m, granule radius (helpers.blade_exit)
# dt = 5e-6 s (ω·dt = 5e-4): measured errors 3.3e-4 / 4.4e-4 (time / speed) at 1e-5 s,
# 1.3e-4 / 1.5e-4 at 3e-6 s, 4.9e-5 / 8.4e-5 at 1e-6 s (first order, symplectic Euler plus the
# contact's position correction); 5e-6 s keeps a 2× margin under the 1e-3 requirement.
DT = 5e-6
TOLERANCE = 1e-3


def test_frictionless_exit_matches_closed_form() -> None:
    t_exact, v_exact = frictionless_exit(OMEGA, X0, 0.0, TIP)
    t, v, offset = blade_exit(OMEGA, X0, 0.0, TIP, DT)
    assert t == pytest.approx(t_exact, rel=TOLERANCE)
    assert v == pytest.approx(v_exact, rel=TOLERANCE)
    # the granule stays on the face: its centre never leaves the line by more than ~the slop
    assert offset < 0.05 * RADIUS
