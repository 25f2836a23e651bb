"""Hard cases of the soft kernel (SoftGranules, perga.contact.soft.polygon_forces): stable, or
refused.

The issue's list at kernel level, each either refused up front with a clear message or run and
checked for: finite states, no granule outside the chamber or through a plate, restitution as
calibrated (0.5 %, the issue's), energy never rising beyond the scheme's discretisation.

* e ∈ {0.05, 0.1, 0.3, 0.7, 1} × f ∈ {0, 0.5, 1}: e ≤ exp(−2) with end="force" refused
  (ValueError naming value and range); with end="overlap" every e runs; impacts on a wall and
  between granules, oblique wall impacts, a 150-granule chamber gas (``GAS_RISE``).
* A kinematic 80 × 6 mm plate at 3000 rpm striking granules at dt = min(t_c/50, tunnelling):
  first-strike speed (1 + e) ω |x|, Jacobi bound 2 ω R for any number of strikes.
* Mass ratio 1:20,000 (0.1 g on a 2 kg FREE or PINNED plate): e on the face, t_c on m_granule.
* Densely overlapping packings (1.3× jammed): ``relax`` then release below √(2 E/m_min); an
  over-full chamber refused.
* A long closed passive run (e = 0.9, f = 0.3, rolling off/on): ``LONG_RISE``.

Case files, Pymunk hinges and stops are tested at the engine level.
"""

import math

import numpy as np
import pytest

from perga.analytic.contact import (
    FORCE_END_MIN_RESTITUTION,
    LinearSpringDashpot,
    damping_ratio,
    time_step,
    tunnelling_time_step,
)
from perga.contact.soft import SoftGranules, chamber, contact_parameters, plane, uniform_table
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_ACTIVE,
    KINEMATIC,
    PINNED,
    contact_table,
    polygon_set,
)
from perga.model.plan import steps_for_damping

from .helpers import chamber_gas, impact

E_VALUES = (0.05, 0.1, 0.3, 0.7, 1.0)
F_VALUES = (0.0, 0.5, 1.0)
RADIUS = 2e-3  # m
MASS = 1e-4  # kg (0.1 g)
K_N = 1e6  # N/m


def _ends(e: float) -> list[str]:
    """End criteria that can reach e: "overlap" always, "force" only above exp(-2)."""
    return ["overlap", "force"] if e > FORCE_END_MIN_RESTITUTION else ["overlap"]


# --- e from 0.05 to 1, f from 0 to 1 ----------------------------------------------------------


@pytest.mark.parametrize("e", [0.05, 0.1])
def test_low_restitution_with_force_end_is_refused(e):
    """e ≤ exp(−2) needs an overdamped force-clamped contact: refused up front, for granule rows
    and for polygon tables (always force-clamped), naming the value and the allowed range."""
    for make in (
        lambda: contact_parameters("linear", e, k_n=K_N, end="force"),
        lambda: contact_parameters("hertz", e, k_n=1e9),  # end="force" is the default
        lambda: contact_table(K_N, 0.3 * K_N, e, 0.5),
    ):
        with pytest.raises(ValueError) as info:
            make()
        message = str(info.value)
        assert f"got {e}" in message
        assert "exp(-2) = 0.135335, 1]" in message
        assert "end='force'" in message


def test_low_restitution_refusal_suggests_overlap_end():
    with pytest.raises(ValueError, match="overlap"):
        contact_parameters("linear", 0.05, k_n=K_N, end="force")


def _oblique_on_wall(row: np.ndarray, v_n: float, v_t: float) -> tuple[SoftGranules, float]:
    """A granule hits the plane y = 0 at (v_t, −v_n); returns the run and the kinetic energy in."""
    g = SoftGranules(
        [[0.0, RADIUS]], [RADIUS], [MASS], uniform_table(row), v=[[v_t, -v_n]],
        walls=[plane((0.0, 0.0), (0.0, 1.0))], v_max=v_n,
    )  # fmt: skip
    g.x[0, 1] = RADIUS + 0.37 * v_n * g.dt
    energy = g.kinetic_energy()
    for _ in range(20_000):
        g.step(1)
        if g.v[0, 1] > 0.0 and g.x[0, 1] > RADIUS + 2.0 * v_n * g.dt:
            return g, energy
    raise AssertionError("the contact did not end")


HEAVY_DAMPING_E_ERROR = 1e-2
"""Allowed relative error of e at t_c/50 for e = 0.05 and 0.1 (end="overlap", ζ = 0.69 and
0.59): measured −0.75 % and −0.64 % over touch phases, second order in dt (−0.17 % and −0.15 %
at t_c/100, where the 0.5 % target is met). The step plan gives such contacts more steps
(``test_heavy_damping_restitution_at_the_planned_step``)."""


@pytest.mark.parametrize("e", E_VALUES)
def test_restitution_matrix_impacts(e):
    """Head-on granule-wall and granule-granule impacts at 10 m/s, f = 0, 0.5, 1, every end
    criterion that can reach e (e = 0.05 and 0.1 only with end="overlap"): e within 0.5 % (the
    issue's) at t_c/50 for e ≥ 0.3; for e ≤ 0.1 within HEAVY_DAMPING_E_ERROR at t_c/50 and 0.5 %
    at t_c/100.

    Oblique wall impacts (30°): finite, normal rebound within 0.5 % of e v_n (or as above),
    tangential velocity change within the Coulomb bound f (1 + e) v_n, and no kinetic energy
    gained beyond 4.1e-4 (at e = 1 the scheme's O(dt²) normal error: e − 1 ≤ 2.05e-4 measured at
    t_c/50 over touch phases, i.e. ≤ 4.1e-4 in energy; friction only removes energy).
    """
    tolerance = 5e-3 if e > 0.2 else HEAVY_DAMPING_E_ERROR
    for end in _ends(e):
        for f in F_VALUES:
            row = contact_parameters("linear", e, k_n=K_N, friction=f, end=end)
            for kind in ("wall", "pair"):
                result = impact("linear", e, 10.0, kind, end=end, params=row)
                assert np.all(np.isfinite(result.granules.x))
                assert result.e == pytest.approx(e, rel=tolerance), (end, f, kind)
                if e < 0.2:
                    fine = impact("linear", e, 10.0, kind, end=end, params=row, dt_fraction=0.01)
                    assert fine.e == pytest.approx(e, rel=5e-3), (end, f, kind)
            v_n, v_t = 10.0 * math.cos(math.pi / 6), 10.0 * math.sin(math.pi / 6)
            g, energy = _oblique_on_wall(row, v_n, v_t)
            assert np.all(np.isfinite(g.v)) and np.isfinite(g.w[0])
            assert g.v[0, 1] == pytest.approx(e * v_n, rel=tolerance), (end, f)
            assert abs(g.v[0, 0] - v_t) <= f * (1.0 + e) * v_n * (1.0 + 1e-9)
            assert g.kinetic_energy() <= energy * (1.0 + 4.1e-4)


def test_heavy_damping_restitution_at_the_planned_step():
    """e = 0.05 and 0.1 (end="overlap", ζ = 0.69, 0.59), granule-granule and -wall at 10 m/s:
    at t_c/50 e misses the 0.5 % target (measured −0.69 %, −0.61 %); at the steps the case's
    step plan gives them for their damping (``steps_for_damping``: 120 and 92) within it
    (measured −0.12 %, −0.17 %)."""
    for e in (0.05, 0.1):
        row = contact_parameters("linear", e, k_n=K_N, friction=0.0, end="overlap")
        fraction = 1.0 / steps_for_damping(damping_ratio(e, "overlap"), 50.0)
        for kind in ("pair", "wall"):
            coarse = impact("linear", e, 10.0, kind, end="overlap", params=row).e
            assert abs(coarse / e - 1.0) > 5e-3
            planned = impact("linear", e, 10.0, kind, end="overlap", params=row,
                             dt_fraction=fraction).e  # fmt: skip
            assert planned == pytest.approx(e, rel=5e-3)


R_CHAMBER = 0.05  # m


def _chamber_gas(n, seed, row, *, speed=3.0):
    """``helpers.chamber_gas`` at 3 m/s per component."""
    return chamber_gas(n, seed, row, speed=speed)


def _energies(g: SoftGranules, steps: int, every: int = 1) -> np.ndarray:
    """E = kinetic + elastic (``SoftGranules.energy``), J, at the start and every ``every`` steps;
    checks finiteness and that every centre stays inside the chamber on the way."""
    energies = [g.energy()]
    for _ in range(steps // every):
        g.step(every)
        assert np.all(np.isfinite(g.x)) and np.all(np.isfinite(g.v)) and np.all(np.isfinite(g.w))
        assert np.all(np.hypot(*g.x.T) < R_CHAMBER)
        energies.append(g.energy())
    return np.array(energies)


def _largest_rise(energies: np.ndarray) -> float:
    """Largest excess of a sample over every earlier one, J (≤ 0 if E never rises)."""
    return float(np.max(energies[1:] - np.maximum.accumulate(energies)[:-1]))


GAS_RISE = 2e-4
"""Largest allowed rise of the sampled energy of the chamber gas over every earlier sample, in
units of E(0). The sampled E = ½ m v² + ½ k δ² pairs velocities half a step old with the
positions (kick-drift), so inside a contact it wobbles by O(ω dt) of that contact's energy and
symplectic Euler's normal error adds O((ω dt)²) per contact (e − 1 ≤ 2e-4 at e = 1, t_c/50);
measured for these gases ≤ 4.9e-5 E(0) (e = 1, f = 0), ≤ 2e-6 for e ≤ 0.3; 2e-4 is 4× that."""


@pytest.mark.parametrize("e", E_VALUES)
def test_restitution_matrix_chamber_gas(e):
    """150 granules at ~3 m/s in the round chamber for 2,000 steps of t_c/50, f = 0, 0.5, 1 (end
    "force" where it can reach e, else "overlap"): finite, inside, overlaps below 5 % of a
    radius, energy never rising by more than GAS_RISE·E(0); it falls by > 5 % for e < 1, by more
    than 10 GAS_RISE for e = 1 with friction, and is conserved within GAS_RISE for e = 1, f = 0."""
    end = _ends(e)[-1]
    for f in F_VALUES:
        row = contact_parameters("linear", e, k_n=K_N, friction=f, end=end)
        g = _chamber_gas(150, 1, row)
        energies = _energies(g, 2000, every=2)
        assert _largest_rise(energies) <= GAS_RISE * energies[0], f
        assert g.max_overlap() < 0.05 * RADIUS
        if e == 1.0 and f == 0.0:
            assert energies[-1] == pytest.approx(energies[0], rel=GAS_RISE)
        elif e == 1.0:  # friction alone: measured −11 % (f = 0.5), −3.7 % (f = 1, more sticking)
            assert energies[-1] < (1.0 - 10.0 * GAS_RISE) * energies[0], f
        else:
            assert energies[-1] < 0.95 * energies[0], f


# --- A kinematic hammer plate at 3000 rpm -------------------------------------------------------

OMEGA = 3000.0 * 2.0 * math.pi / 60.0  # rad/s
PLATE = np.array([[0.10, -0.003], [0.18, -0.003], [0.18, 0.003], [0.10, 0.003]])  # 80 × 6 mm, m
R_CORNER = math.hypot(0.18, 0.003)  # farthest point of the plate from the axis, m


def _rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _plate_pose(angle: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World vertices, centre and centre velocity of the plate turned by ``angle`` about (0, 0)."""
    vertices = PLATE @ _rotation(angle).T
    com = vertices.mean(axis=0)
    return vertices, com, OMEGA * np.array([-com[1], com[0]])


@pytest.mark.parametrize("e", [0.3, 0.7, 1.0])
def test_kinematic_plate_at_3000_rpm_strikes_granules(e):
    """An 80 × 6 mm plate from 100 to 180 mm on a rotor at 3000 rpm (tip 56.6 m/s, KINEMATIC)
    strikes four 0.1 g granules at rest, f = 0, 0.5, 1, at dt = min(t_c/50, tunnelling bound)
    (``analytic.contact.time_step``, v_rel,max = 3 ω R_corner: contact-governed here).

    No NaN; no granule centre ever inside the plate (on the face span its distance from the
    mid-plane stays above the half-thickness; peak overlap ≈ 0.5 mm of 2 mm). The first strike
    sends each granule off at (1 + e) ω |x|: a body at rest hit by a face moving at V_n normal to
    it (ω |x| here, the face's tangential speed ω·3 mm being negligible) gets (1 + e) V_n, within
    0.5 % (the calibration of e; measured ≤ 0.12 %), and at most (1 + e)√(1 + f²)·ω R_corner
    (|J_t| ≤ f J_n). At e = 0.3 the innermost granule, flying straight, is caught again by the
    faster outer part of the face (struck 2-3 times, leaving at 1.33-1.53 (1 + e) ω |x|); for any
    number of contacts the bound is 2 ω (R_corner + r): in the plate's frame a passive contact
    cannot raise the Jacobi integral ½ v_rot² − ½ ω² |x|², which is 0 for a granule at rest, so
    |v| ≤ |v_rot| + ω|x| ≤ 2 ω |x| (measured ≤ 0.95 (1 + e) ω R_corner).
    """
    # Four granules ahead of the leading face (y > 0 in the plate's frame), 1-13 mm from it.
    x0 = np.array([[rho, 0.006 + 0.004 * k] for k, rho in enumerate((0.11, 0.13, 0.15, 0.17))])
    n = len(x0)
    t_c = LinearSpringDashpot.from_stiffness(K_N, e, MASS, "force").duration
    steps = time_step(t_c, RADIUS, 0.006, 3.0 * OMEGA * R_CORNER)
    assert steps.governed_by == "contact"
    assert steps.tunnelling == pytest.approx(
        tunnelling_time_step(RADIUS, 0.006, 3 * OMEGA * R_CORNER)
    )
    for f in F_VALUES:
        vertices, com, velocity = _plate_pose(0.0)
        plate = polygon_set(
            [vertices], com[None], kind=[KINEMATIC], velocity=velocity[None], omega=[OMEGA]
        )
        g = SoftGranules(
            x0, np.full(n, RADIUS), np.full(n, MASS),
            uniform_table(contact_parameters("linear", e, k_n=K_N, friction=f)), dt=steps.dt,
            polygons=plate, polygon_table=contact_table(K_N, 2.0 / 7.0 * K_N, e, f),
        )  # fmt: skip
        active = np.zeros(n, bool)
        strikes = np.zeros(n, int)
        first = np.full(n, np.nan)
        lowest = np.inf
        for _ in range(20_000):
            plate.set_pose(0, *_plate_pose(OMEGA * g.time), OMEGA)
            g.step(1)
            assert np.all(np.isfinite(g.x)) and np.all(np.isfinite(g.v))
            local = g.x @ _rotation(OMEGA * g.time)  # plate frame
            on_face = (local[:, 0] >= 0.10) & (local[:, 0] <= 0.18)
            lowest = min(lowest, local[on_face, 1].min(initial=np.inf))
            now = g.polygon_hist[:, 0, HIST_ACTIVE] != 0.0
            strikes += now & ~active
            ended = active & ~now & np.isnan(first)
            first[ended] = np.linalg.norm(g.v[ended], axis=1)
            active = now
            leaving = (np.hypot(*g.x.T) > R_CORNER + RADIUS) & (np.sum(g.x * g.v, axis=1) > 0)
            if np.all(leaving) and not np.any(active):
                break
        else:
            raise AssertionError("granules still within reach of the plate")
        assert lowest > 0.003, f
        assert np.all(strikes >= 1)
        np.testing.assert_allclose(first, (1.0 + e) * OMEGA * np.hypot(*x0.T), rtol=5e-3)
        assert first.max() <= (1.0 + e) * math.sqrt(1.0 + f * f) * OMEGA * R_CORNER
        speeds = np.linalg.norm(g.v, axis=1)
        np.testing.assert_allclose(speeds[strikes == 1], first[strikes == 1], rtol=1e-12)
        assert speeds.max() <= 2.0 * OMEGA * (R_CORNER + RADIUS)


# --- Granule/hammer mass ratio 1:20,000 ----------------------------------------------------------

HAMMER_MASS = 2.0  # kg: 20,000 × the 0.1 g granule
HAMMER = np.array([[-0.04, -0.003], [0.04, -0.003], [0.04, 0.003], [-0.04, 0.003]])  # local, m


class Hammer:
    """The 80 × 6 mm, 2 kg plate as a FREE body (centre at the origin) or PINNED at its end
    (−40, 0) mm, integrated here by the granules' symplectic Euler from the loads the kernel
    returns (kick with this step's load, then pose at the new velocity)."""

    def __init__(self, kind: int):
        self.kind = kind
        self.inertia_c = HAMMER_MASS * (0.08**2 + 0.006**2) / 12.0  # about the centre, kg·m²
        self.pivot = np.array([-0.04, 0.0])
        self.inertia = self.inertia_c + (HAMMER_MASS * 0.04**2 if kind == PINNED else 0.0)
        self.com = np.zeros(2)
        self.angle = 0.0
        self.velocity = np.zeros(2)
        self.omega = 0.0
        vertices, com, velocity = self.pose()
        self.set = polygon_set(
            [vertices], com[None], kind=[kind], mass=[HAMMER_MASS], inertia=[self.inertia],
            pivot=self.pivot[None], velocity=velocity[None], omega=[0.0],
        )  # fmt: skip

    def pose(self):
        rot = _rotation(self.angle)
        if self.kind == PINNED:
            com = self.pivot + rot @ -self.pivot
            arm = com - self.pivot
            velocity = self.omega * np.array([-arm[1], arm[0]])
        else:
            com, velocity = self.com, self.velocity
        return com + HAMMER @ rot.T, com, velocity

    def advance(self, dt: float) -> None:
        force, torque = self.set.force[0], self.set.torque[0]
        if self.kind == FREE:
            self.velocity = self.velocity + force / HAMMER_MASS * dt
            self.com = self.com + self.velocity * dt
            self.omega += torque / self.inertia * dt
        else:
            arm = self.pose()[1] - self.pivot
            moment = torque + arm[0] * force[1] - arm[1] * force[0]  # about the pivot
            self.omega += moment / self.inertia * dt
        self.angle += self.omega * dt
        self.set.set_pose(0, *self.pose(), self.omega)

    def surface_velocity(self, p: np.ndarray) -> np.ndarray:
        _, com, velocity = self.pose()
        return velocity + self.omega * np.array([-(p - com)[1], (p - com)[0]])

    def kinetic_energy(self) -> float:
        if self.kind == FREE:
            return (
                0.5 * HAMMER_MASS * self.velocity @ self.velocity
                + 0.5 * self.inertia * self.omega**2
            )
        return 0.5 * self.inertia * self.omega**2


@pytest.mark.parametrize("kind", [FREE, PINNED], ids=["free", "pinned"])
@pytest.mark.parametrize("e", [0.3, 0.7, 1.0])
def test_mass_ratio_1_to_20000(kind, e):
    """A 0.1 g granule hits a 2 kg plate (FREE, or PINNED at one end and hit 30 mm from its free
    end) at 30 m/s on its face, f = 0.5, 30° incidence.

    The contact step follows the granule, not the hammer: ``SoftGranules.t_c`` (the granule-pair
    row made soft so that the polygon contact is the shortest) is the duration on the granule's
    mass m within ½ m/m_p (t_c ∝ √m_eff, m_eff = 1/(1/m + 1/m_p); the effective mass m_p of the
    plate at its most yielding point is ~0.5 kg, m/m_p ≤ 2e-4), far below the duration on the
    hammer's mass (141× longer). The relative normal velocity at the contact point rebounds at e
    within 0.5 % (the issue's; measured ≤ 0.15 %); the hammer's kinetic energy stays below the
    granule's initial one times 4 m/m_p (a rigid hit gives it at most 4 m/m_p; measured ≤ 1.8e-4),
    no NaN, and the pair loses energy (e < 1; friction: −1.7 % at e = 1) or keeps it within 4.1e-4.
    """
    hammer = Hammer(kind)
    table = contact_table(K_N, 2.0 / 7.0 * K_N, e, 0.5)
    soft = contact_parameters("linear", 1.0, k_n=1e-3 * K_N, friction=0.0)
    hit = np.array([0.01 if kind == PINNED else 0.0, 0.003 + RADIUS])
    v0, angle = 30.0, math.radians(30.0)
    v = np.array([v0 * math.sin(angle), -v0 * math.cos(angle)])
    g = SoftGranules(
        [hit], [RADIUS], [MASS], uniform_table(soft), v=[v],
        polygons=hammer.set, polygon_table=table,
    )  # fmt: skip
    rho = math.hypot(0.04, 0.003)  # bounding radius about the centre of mass, m
    if kind == FREE:  # most yielding point: arm rho (an upper bound on any contact's arm)
        inv_mp = 1.0 / HAMMER_MASS + rho**2 / hammer.inertia
    else:
        inv_mp = (rho + 0.04) ** 2 / hammer.inertia
    t_c_granule = LinearSpringDashpot.from_stiffness(K_N, e, MASS, "force").duration
    assert g.t_c <= t_c_granule
    assert MASS * inv_mp < 2.5e-4
    assert g.t_c == pytest.approx(t_c_granule, rel=0.51 * MASS * inv_mp)
    assert LinearSpringDashpot.from_stiffness(K_N, e, HAMMER_MASS, "force").duration > 100 * g.t_c
    g.x[0] -= 0.37 * g.dt * v
    energy0 = g.kinetic_energy()
    v_n0 = None
    touched = False
    for _ in range(5_000):
        hammer.set.set_pose(0, *hammer.pose(), hammer.omega)
        g.step(1)
        hammer.advance(g.dt)
        assert np.all(np.isfinite(g.x)) and np.isfinite(hammer.omega)
        active = g.polygon_hist[0, 0, HIST_ACTIVE] != 0.0
        touched |= active
        if touched and not active:
            break
    else:
        raise AssertionError("the contact did not end")
    normal = _rotation(hammer.angle) @ np.array([0.0, 1.0])
    point = g.x[0] - RADIUS * normal
    v_n0 = -(v @ np.array([0.0, 1.0]))
    v_n1 = (g.v[0] - hammer.surface_velocity(point)) @ normal
    assert v_n1 / v_n0 == pytest.approx(e, rel=5e-3)
    assert hammer.kinetic_energy() < 4.0 * MASS * inv_mp * energy0
    total = g.kinetic_energy() + hammer.kinetic_energy()
    if e < 1.0:
        assert total < energy0
    else:
        assert total <= energy0 * (1.0 + 4.1e-4)


# --- Densely overlapping packings --------------------------------------------------------------

PHI_JAMMED = 0.84
"""Random jammed packing fraction of bidisperse-like discs in 2-D (O'Hern et al., PRE 68 (2003)
011306: 0.84), dimensionless."""


def _overlapping_packing(n: int, phi_chamber: float, seed: int = 7) -> SoftGranules:
    """n granules (0.8-1.2 RADIUS) thrown at random into a central disc at 1.3× the jammed packing
    fraction (overlaps up to ~2 radii), in a round chamber of area fraction ``phi_chamber``
    (capped by the central disc), e = 0.7, f = 0.5, at rest, no gravity."""
    rng = np.random.default_rng(seed)
    r = RADIUS * rng.uniform(0.8, 1.2, n)
    area = float(np.sum(np.pi * r**2))
    r_chamber = math.sqrt(area / (phi_chamber * math.pi))
    r_pack = min(math.sqrt(area / (1.3 * PHI_JAMMED * math.pi)), r_chamber) - 1.2 * RADIUS
    radius = r_pack * np.sqrt(rng.uniform(0.0, 1.0, n))
    angle = rng.uniform(0.0, 2.0 * math.pi, n)
    row = contact_parameters("linear", 0.7, k_n=K_N, friction=0.5)
    return SoftGranules(
        np.column_stack([radius * np.cos(angle), radius * np.sin(angle)]), r,
        MASS * (r / RADIUS) ** 2, uniform_table(row), walls=[chamber(r_chamber)],
    )  # fmt: skip


def _release(g: SoftGranules, steps: int) -> None:
    """After ``relax``: run ``steps`` steps; no granule faster than √(2 E/m_min) (E: the energy
    left after relaxing, all elastic, which a passive system cannot exceed), E non-increasing
    (GAS_RISE·E(0)), all inside the chamber."""
    r_chamber = g.walls[0, 3]
    energy = g.energy()
    bound = math.sqrt(2.0 * energy / g.m.min())
    energies = [energy]
    for _ in range(steps // 10):
        g.step(10)
        assert np.all(np.isfinite(g.x)) and np.all(np.hypot(*g.x.T) < r_chamber)
        assert np.hypot(*g.v.T).max() <= bound
        energies.append(g.energy())
    assert _largest_rise(np.array(energies)) <= GAS_RISE * energy


def test_dense_overlapping_packing_relaxed_then_released():
    """300 granules at 1.3× the jammed packing (central disc, overlaps up to 2 radii; released as
    they are they would fly at ~500 m/s, ``release_speed``) in a chamber at φ = 0.5: ``relax``
    (default v_release 0.01 m/s) resolves them (measured 36,800 steps), then 2,000 free steps:
    speeds below √(2 E/m_min) (measured 0.005 of 0.032 m/s), energy never rising."""
    g = _overlapping_packing(300, 0.5)
    assert g.max_overlap() > 1.5 * RADIUS
    assert g.release_speed() > 100.0
    g.relax()
    assert g.max_overlap() < 1e-3 * RADIUS
    _release(g, 2000)


@pytest.mark.slow
def test_dense_overlapping_packing_of_2000_granules():
    """As above with 2,000 granules (chamber radius 127 mm): relax needs 211,800 steps (~40 s),
    more than its default max_steps = 200,000 (``max_steps`` raised here)."""
    g = _overlapping_packing(2000, 0.5)
    g.relax(max_steps=400_000)
    assert g.max_overlap() < 1e-3 * RADIUS
    _release(g, 2000)


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    raises=RuntimeError,
    reason="relax() with its default max_steps = 200,000 gives up on 2,000 granules at 1.3× the "
    "jammed packing in a chamber at φ = 0.5 (needs 211,800 steps) and blames the density",
)
def test_dense_overlapping_packing_of_2000_granules_with_defaults():
    _overlapping_packing(2000, 0.5).relax()


def test_overfull_chamber_is_refused():
    """100 granules whose total area is 1.09× the chamber's (more than any packing, ≤ 0.9069,
    can hold): ``relax`` raises RuntimeError naming the steps, the release speed and the density
    (after its max_steps, ~4 s: there is no up-front area check)."""
    g = _overlapping_packing(100, 1.3 * PHI_JAMMED)
    with pytest.raises(RuntimeError, match=r"not resolved after \d+ steps.*too dense"):
        g.relax()


# --- Long closed passive run ----------------------------------------------------------------

LONG_RISE = 2e-5
"""Largest allowed rise of the sampled energy over every earlier sample, in units of the energy
at that sample. E = kinetic + elastic pairs velocities half a step old with the positions, so it
wobbles by O(ω dt) of the energy stored in contacts (≤ 4.5 % of E in these gases) and each
contact carries symplectic Euler's O((ω dt)²) error; with e = 0.9 the losses dominate: measured
≤ 2.2e-6 with and without rolling resistance, over 5,000 steps sampled every step and 10⁵ steps
sampled every 10."""


def _long_run(rolling: float, steps: int, every: int) -> None:
    row = contact_parameters("linear", 0.9, k_n=K_N, friction=0.3, rolling=rolling)
    g = _chamber_gas(150, 3, row)
    energies = _energies(g, steps, every)
    rises = energies[1:] - np.maximum.accumulate(energies)[:-1]
    assert np.all(rises <= LONG_RISE * energies[1:])
    assert energies[-1] < energies[0]


@pytest.mark.parametrize("rolling", [0.0, 0.1])
def test_long_run_energy_never_rises(rolling):
    """150 granules, e = 0.9, f = 0.3, rolling resistance off and on, 5,000 steps of t_c/50
    sampled every step: finite, inside the chamber, E never rising beyond LONG_RISE."""
    _long_run(rolling, 5_000, 1)


@pytest.mark.slow
@pytest.mark.parametrize("rolling", [0.0, 0.1])
def test_long_run_energy_never_rises_1e5_steps(rolling):
    """As above for 200,000 steps sampled every 10 (E falls to ~3 % of E(0))."""
    _long_run(rolling, 200_000, 10)
