"""A soft contact on a face that turns with the rotor: the kernel against an independent
integration of the same law.

A granule shot at a hammer welded to a turning rotor rebounds, relative to the face, with
another e than the one asked for: during the contact (t_c = 0.1 ms) the face's frame turns,
and the granule, sliding along the face, is pressed onto it by the Coriolis force and pulled
off it by the centrifugal force (relative acceleration along the face's normal
ω²(r·n) − 2ω u_t). At 1 m/s of approach on a rotor at 1500 rpm with e = 0.05 (where e·u is
0.05 m/s) that is −39 % of e; on a face at rest it is nothing. The kernel gives what the law
gives: the same shot integrated with solve_ivp (rtol 1e-11) from the kernel's own state before
the contact, in the inertial frame, rebounds the same to within the kernel's step error (on a
face at rest −0.12 % at the step plan's t_c/120 for this damping; here 0.3 % is allowed)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from perga.analytic.contact import LinearSpringDashpot
from perga.case import load_case
from perga.engine import Simulation
from perga.model.compile import compile_case

CASE = Path(__file__).resolve().parents[3] / "cases" / "rebound-test.toml"
E, DURATION, HALF_WIDTH = 0.05, 1e-4, 0.01


def _face(theta: float) -> tuple[np.ndarray, np.ndarray]:
    """The welded plate's leading face's outward normal and the radial direction at the rotor's
    angle ``theta`` (the plate lies along the radius, its face HALF_WIDTH off it)."""
    return np.array([-math.sin(theta), math.cos(theta)]), np.array(
        [math.cos(theta), math.sin(theta)]
    )


def _shot(omega: float, speed: float) -> tuple[float, float]:
    """e of the kernel (−u_n after/u_n before, relative to the face's material point, tracked
    step by step) and of solve_ivp from the kernel's state ten steps before the contact."""
    sets = ['contact_model.kind="linear"', f"contact_model.duration={DURATION}",
            'contact_model.end="overlap"', f"contacts[0].restitution={E}",
            "contacts[0].friction=0.0",
            f"granules.placement.speed={speed}", "granules.placement.angle=0.0",
            f"rotor.omega={omega!r}", "hammers.hinge_radius=0.08",
            "hammers.shape={kind='plate', length=0.06, width=0.02, hinge_offset=0.005}",
            'solver.dt="auto"']  # fmt: skip
    system = compile_case(load_case(CASE, overrides=sets))
    sim = Simulation(system, track_energy=False)
    m, r = system.granules[0].mass, system.granules[0].radius

    def state() -> tuple[np.ndarray, np.ndarray, float, bool]:
        frame = sim.frame()
        g = frame.granules
        return g.positions[0], g.velocities[0], frame.machine.axis_angles[0], bool(g.contacts[0])

    def normal_speed(p: np.ndarray, v: np.ndarray, theta: float) -> float:
        n, radial = _face(theta)
        return float(v @ n - omega * (p @ radial))  # v_n less the face's ω × p along n

    history, ended = [state()], None
    with sim.running():
        while ended is None:
            sim.step()
            history.append(state())
            if history[-2][3] and not history[-1][3]:
                ended = len(history) - 1
    first = next(i for i, s in enumerate(history) if s[3])
    kernel = -normal_speed(*history[ended][:3]) / normal_speed(*history[first - 1][:3])

    p0, v0, theta0, _ = history[first - 10]
    law = LinearSpringDashpot.from_duration(DURATION, E, m, "overlap")

    def overlap_and_rate(t: float, y: np.ndarray) -> tuple[float, float, np.ndarray]:
        n, radial = _face(theta0 + omega * t)
        return r - (y[:2] @ n - HALF_WIDTH), -(y[2:] @ n - omega * (y[:2] @ radial)), n

    def rhs(t: float, y: np.ndarray) -> list[float]:
        delta, rate, n = overlap_and_rate(t, y)
        force = law.k * delta + law.c * rate if delta > 0 else 0.0
        return [y[2], y[3], force * n[0] / m, force * n[1] / m]

    def touches(t: float, y: np.ndarray) -> float:
        return overlap_and_rate(t, y)[0]

    touches.terminal, touches.direction = True, 1
    flight = solve_ivp(rhs, (0.0, 1e-2), [*p0, *v0], method="DOP853", rtol=1e-11, atol=1e-14,
                       events=touches)  # fmt: skip
    t1, y1 = flight.t_events[0][0], flight.y_events[0][0]

    def leaves(t: float, y: np.ndarray) -> float:
        return -overlap_and_rate(t, y)[0] if t > t1 + 1e-7 else 1.0

    leaves.terminal, leaves.direction = True, 1
    contact = solve_ivp(rhs, (t1, t1 + 5 * DURATION), y1, method="DOP853", rtol=1e-11,
                        atol=1e-14, events=leaves, max_step=DURATION / 200)  # fmt: skip
    t2, y2 = contact.t_events[0][0], contact.y_events[0][0]
    theta = lambda t: theta0 + omega * t  # noqa: E731
    reference = -normal_speed(y2[:2], y2[2:], theta(t2)) / normal_speed(y1[:2], y1[2:], theta(t1))
    return kernel, reference


@pytest.mark.parametrize(
    ("rpm", "speed", "deviation"),
    [(0.0, 1.0, 0.0), (1500.0, 1.0, -0.39), (2700.0, 10.0, -0.0062), (2700.0, 40.0, +0.0047)],
)
def test_the_kernel_rebounds_as_the_law_on_a_turning_face(
    rpm: float, speed: float, deviation: float
) -> None:
    """At rest (ω = 1e-6 rad/s) both give the asked e (the kernel to its step error); at
    1500 rpm and 1 m/s both give e 39 % low; at 2700 rpm (a 140 mm tip at 40 m/s) and 10 or
    40 m/s the law's own −0.62 and +0.47 % (the reference, to 5e-4 of e): the turning face's
    share of the restitution table's fast cells (docs/dev/validation.md). The kernel agrees with
    the reference to 0.3 % of e (measured 0.03-0.11 % at 2700 rpm)."""
    kernel, reference = _shot(max(rpm * 2 * math.pi / 60, 1e-6), speed)
    assert reference / E - 1 == pytest.approx(deviation, abs=5e-4 if rpm > 1500 else 5e-3)
    assert kernel == pytest.approx(reference, rel=3e-3)
