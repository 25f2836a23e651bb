"""The elastic energy stored in soft contacts, as energy.csv records it, against the potential of
each force law; its place in the ledger (kinetic + elastic conserved through an elastic
collision; a row's residual from its own columns)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from perga.engine import Simulation
from perga.model import ContactSpec, GranuleSpec, RotorSpec, System
from perga.model.records import Events
from perga.model.system import RigidContactSpec, SoftContactSpec
from perga.output.recorders import EnergyRecorder
from perga.output.tables import read_columns
from tests.engine.helpers import plate

R = 0.002  # m, granule radius
M = 5e-5  # kg, granule mass
T_C = 1e-4  # s, the linear contact's duration
K_LINEAR = 0.5 * M * (math.pi / T_C) ** 2  # N/m: t_c = π √(m_eff / k), m_eff = m/2
K_HERTZ = 1e8  # Pa: (4/3) E*, the contact stiffness k_n √R*


def _pair(law: str | None, gap: float, speed: float, gravity: float = 0.0) -> System:
    """Two granules on the x axis, centres 2R + ``gap`` apart (gap < 0: overlapping), moving
    towards each other at ``speed`` each; frictionless, e = 1; soft with ``law``, or rigid."""
    stiffness = {"linear": K_LINEAR, "hertz": K_HERTZ, None: None}[law]
    half = R + 0.5 * gap
    return System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2),
        hammers=(
            plate(
                0.05,
                0.06,
                -0.005,
                0.005,
                0.05,
                hinge_radius=0.0,
                angle_on_rotor=0.0,
                mount="welded",
                material="steel",
            ),
        ),  # far off: the soft model needs one
        granules=tuple(
            GranuleSpec(
                position=(s * half, 0.0),
                velocity=(-s * speed, 0.0),
                radius=R,
                mass=M,
                material="bb",
            )
            for s in (-1, 1)
        ),
        contacts=(
            ContactSpec("bb", "bb", restitution=1.0, friction=0.0, stiffness=stiffness),
            ContactSpec("bb", "steel", restitution=1.0, friction=0.0, stiffness=stiffness),
        ),
        granule_dt=T_C / 1000,
        gravity=(0.0, gravity),
        granule_collisions=True,
        contact_model=SoftContactSpec(law) if law else RigidContactSpec(),
    )


def _recorded(sim: Simulation, tmp_path: Path, times: list[float]) -> dict[str, np.ndarray]:
    """energy.csv of ``sim`` with a frame now and after each time of ``times`` (s) from now."""
    recorder = EnergyRecorder(tmp_path, sim.spec)
    recorder.record(sim.frame(), Events())
    for t in times:
        sim.run(t)
        recorder.record(sim.frame(), Events())
    recorder.close()
    return read_columns(tmp_path / "energy.csv")


@pytest.mark.parametrize(
    ("law", "potential"),
    [
        ("linear", lambda d: 0.5 * K_LINEAR * d**2),  # F = k δ
        ("hertz", lambda d: 0.4 * K_HERTZ * math.sqrt(R / 2) * d**2.5),  # F = k_n √R* δ^{3/2}
    ],
)
def test_a_pressed_pair_stores_the_potential_of_its_force_law(law, potential, tmp_path) -> None:
    """Two granules at rest, overlapping by δ = 20 µm: energy.csv's elastic energy is the
    potential of the law's spring, ∫F dδ, to 1e-9 (rounding only)."""
    delta = 2e-5
    energy = _recorded(Simulation(_pair(law, -delta, 0.0)), tmp_path, [])
    assert energy["elastic"][0] == pytest.approx(potential(delta), rel=1e-9)
    assert energy["elastic"][0] > 0


def test_an_elastic_collision_keeps_kinetic_plus_elastic_energy(tmp_path) -> None:
    """A head-on frictionless collision, e = 1, linear, sampled at a tenth of the contact
    duration apart through it (under in-plane gravity across the line of centres): kinetic +
    elastic − gravity's work stays the kinetic energy at the start. Tolerance ω dt: symplectic
    Euler keeps ½mv² + ½kx² within ½ m ω² dt |x v| ≤ (ω dt / 2) E of its conserved shadow
    energy (ω = π / t_c, dt = t_c/1000: 3.1e-3); with the elastic energy left out the sum
    falls to 0.5 mid-contact. Each row's residual is its columns' balance to rounding."""
    speed = 1.0
    sim = Simulation(_pair("linear", speed * T_C / 100, speed, gravity=-9.80665))
    energy = _recorded(sim, tmp_path, [T_C / 200] + [T_C / 10] * 11)
    start = energy["kinetic"][0]
    total = energy["kinetic"] + energy["elastic"] - energy["gravity_work"]
    assert np.max(energy["elastic"]) > 0.4 * start  # sampled mid-contact
    assert energy["elastic"][-1] == 0.0  # and after it
    assert np.abs(total / start - 1.0).max() < math.pi / 1000
    balance = (
        energy["drive_work"] + energy["gravity_work"] + energy["joint_correction"]
        + energy["inflow"] - energy["outflow"] - (energy["kinetic"] - start)
        - (energy["elastic"] - energy["elastic"][0]) - energy["contact_dissipation"]
        - energy["friction"] - energy["drag"]
    )  # fmt: skip
    assert np.abs(balance - energy["residual"]).max() < 1e-12 * start


def test_rigid_contacts_store_none(tmp_path) -> None:
    """Rigid contacts hold no energy: energy.csv's elastic column is 0 before, during and
    after a collision."""
    energy = _recorded(Simulation(_pair(None, 1e-5, 1.0)), tmp_path, [1e-5, 1e-5])
    assert energy["elastic"].tolist() == [0.0, 0.0, 0.0]
    assert energy["kinetic"][-1] == pytest.approx(energy["kinetic"][0], rel=1e-9)
