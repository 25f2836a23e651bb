"""Frictionless bead on a radial blade of a rotor at constant ω (design §4 closed form)."""

from __future__ import annotations

import pytest

from perga.analytic.sliding import frictionless_exit
from perga.engine import (
    ContactSpec,
    GranuleSpec,
    RotorSpec,
    SceneSpec,
    Simulation,
    build_scene,
)
from tests.engine.helpers import plate, rotating_frame

OMEGA = 100.0  # rad/s
X0 = 0.05  # m, start radius
TIP = 0.15  # m, blade tip
RADIUS = 0.002  # m
THICKNESS = 0.004  # m, blade thickness
# dt = 5e-6 s (ω·dt = 5e-4): measured errors 3.3e-4 / 4.4e-4 (time / speed) at 1e-5 s,
# 1.3e-4 / 1.5e-4 at 3e-6 s, 4.9e-5 / 8.4e-5 at 1e-6 s (first order, symplectic Euler plus the
# contact's position correction); 5e-6 s keeps a 2× margin under the 1e-3 requirement.
DT = 5e-6
TOLERANCE = 1e-3


def _exit(dt: float) -> tuple[float, float, float]:
    """Exit time (s), relative exit speed (m/s) and largest |offset| from the centre line (m),
    interpolated linearly between the two steps around the crossing of x = TIP."""
    # the leading face (y = -RADIUS) is offset by the granule radius so that the granule's
    # centre line passes through the axis; Coriolis presses the granule onto it
    blade = plate(
        0.0, TIP, -RADIUS - THICKNESS, -RADIUS, 0.1,
        hinge_radius=0.0, angle_on_rotor=0.0, mount="welded", material="steel",
    )  # fmt: skip
    granule = GranuleSpec(
        position=(X0, 0.0),
        velocity=(0.0, OMEGA * X0),  # at rest relative to the blade
        radius=RADIUS,
        mass=50e-6,
        material="beebread",
        rolls=False,
        angular_velocity=OMEGA,
    )
    spec = SceneSpec(
        rotor=RotorSpec(omega=OMEGA, radius=0.2),
        hammers=(blade,),
        granules=(granule,),
        # e = 0: a sustained contact re-applies e to each step's small approach speed
        contacts=(ContactSpec("beebread", "steel", restitution=0.0, friction=0.0),),
        dt=dt,
    )
    sim = Simulation(build_scene(spec))
    previous = (sim.time, *rotating_frame(sim, OMEGA))
    offset = 0.0
    while True:
        sim.step()
        current = (sim.time, *rotating_frame(sim, OMEGA))
        if current[1] >= TIP:
            s = (TIP - previous[1]) / (current[1] - previous[1])
            t = previous[0] + s * (current[0] - previous[0])
            v = previous[2] + s * (current[2] - previous[2])
            return t, v, offset
        offset = max(offset, abs(current[3]))
        previous = current


def test_frictionless_exit_matches_closed_form() -> None:
    t_exact, v_exact = frictionless_exit(OMEGA, X0, 0.0, TIP)
    t, v, offset = _exit(DT)
    assert t == pytest.approx(t_exact, rel=TOLERANCE)
    assert v == pytest.approx(v_exact, rel=TOLERANCE)
    # the granule stays on the face: its centre never leaves the line by more than ~the slop
    assert offset < 0.05 * RADIUS
