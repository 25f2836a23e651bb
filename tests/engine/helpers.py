"""Builders shared by the engine tests (SI units throughout)."""

from __future__ import annotations

import math

import numpy as np

from perga.engine import HammerSpec, Simulation


def rectangle(x0: float, x1: float, y0: float, y1: float) -> tuple[tuple[float, float], ...]:
    """Counter-clockwise rectangle outline, m."""
    return ((x0, y0), (x1, y0), (x1, y1), (x0, y1))


def plate(x0: float, x1: float, y0: float, y1: float, mass: float, **kwargs) -> HammerSpec:
    """A uniform rectangular hammer with exact mass properties about the frame origin."""
    length, width = x1 - x0, y1 - y0
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    moment = mass * (length**2 + width**2) / 12 + mass * (cx**2 + cy**2)
    return HammerSpec(
        outline=rectangle(x0, x1, y0, y1),
        mass=mass,
        moment_about_hinge=moment,
        centre_of_mass=(cx, cy),
        **kwargs,
    )


def rotating_frame(sim: Simulation, omega: float) -> tuple[float, float, float]:
    """Granule 0's radial coordinate (m), its velocity relative to the rotor along the rotor's
    x-axis (m/s), and its coordinate across it (m), in the rotor frame."""
    theta = sim.rotor_angle()
    ex = np.array([math.cos(theta), math.sin(theta)])
    ey = np.array([-math.sin(theta), math.cos(theta)])
    p = sim.granule_positions()[0]
    v = sim.granule_velocities()[0]
    v_rel = v - omega * np.array([-p[1], p[0]])
    return float(p @ ex), float(v_rel @ ex), float(p @ ey)
