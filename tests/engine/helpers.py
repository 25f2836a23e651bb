"""Builders shared by the engine tests (SI units throughout)."""

from __future__ import annotations

import math

import numpy as np

from perga.engine import Simulation
from perga.model import ContactSpec, EffectsSpec, GranuleSpec, HammerSpec, RotorSpec, System


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
    theta = sim.frame().machine.rotor_angle
    ex = np.array([math.cos(theta), math.sin(theta)])
    ey = np.array([-math.sin(theta), math.cos(theta)])
    p = sim.frame().granules.positions[0]
    v = sim.frame().granules.velocities[0]
    v_rel = v - omega * np.array([-p[1], p[0]])
    return float(p @ ex), float(v_rel @ ex), float(p @ ey)


def blade_exit(
    omega: float,
    x0: float,
    v0: float,
    tip: float,
    dt: float,
    *,
    face_friction: float = 0.0,
    rolls: bool = False,
    spin: float = 0.0,
    effects: EffectsSpec | None = None,
    radius: float = 0.002,
    thickness: float = 0.004,
) -> tuple[float, float, float]:
    """A granule on the leading face of a welded radial blade (ω constant) starting at x0 with
    outward speed v0 and angular velocity ``spin`` (rad/s) relative to the blade. Returns the
    exit time (s) and relative exit speed (m/s), interpolated linearly between the two steps
    around x = tip, and the largest |offset| of its centre from the blade's centre line (m).

    The leading face (y = −radius) is offset by the granule radius so that the granule's centre
    line passes through the axis; Coriolis presses the granule onto it. e = 0: a sustained
    contact re-applies e to each step's small approach speed."""
    blade = plate(
        0.0, tip, -radius - thickness, -radius, 0.1,
        hinge_radius=0.0, angle_on_rotor=0.0, mount="welded", material="steel",
    )  # fmt: skip
    granule = GranuleSpec(
        position=(x0, 0.0),
        velocity=(v0, omega * x0),
        radius=radius,
        mass=50e-6,
        material="beebread",
        rolls=rolls,
        angular_velocity=omega + spin,
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=omega, radius=0.2),
        hammers=(blade,),
        granules=(granule,),
        contacts=(ContactSpec("beebread", "steel", restitution=0.0, friction=face_friction),),
        granule_dt=dt,
        effects=effects or EffectsSpec(),
    )
    sim = Simulation(spec, record_impacts=False, track_energy=False)
    previous = (sim.time, *rotating_frame(sim, omega))
    offset = 0.0
    while True:
        sim.step()
        current = (sim.time, *rotating_frame(sim, omega))
        if current[1] >= tip:
            s = (tip - previous[1]) / (current[1] - previous[1])
            t = previous[0] + s * (current[0] - previous[0])
            v = previous[2] + s * (current[2] - previous[2])
            return t, v, offset
        offset = max(offset, abs(current[3]))
        previous = current
