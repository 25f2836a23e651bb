"""Granule-polygon soft contacts (perga.contact.soft.polygon_forces): geometry, restitution,
conservation."""

import math

import numba
import numpy as np
import pytest

from perga.analytic.contact import HertzTsuji, LinearSpringDashpot
from perga.contact.soft import SoftGranules, contact_parameters, uniform_table
from perga.contact.soft.polygon_forces import contact_energy, polygon_contacts
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_ACTIVE,
    HIST_COLUMNS,
    HIST_DISSIPATED,
    HIST_NORMAL_IMPULSE,
    HIST_RATE,
    HIST_SLIP,
    HIST_TANGENTIAL_IMPULSE,
    HIST_XI,
    KINEMATIC,
    PINNED,
    contact_table,
    polygon_set,
)

R = 2.5e-3  # granule radius, m
M_DISC = 1.6e-4  # granule mass, kg
I_DISC = 0.5 * M_DISC * R * R
K_N = 1e6  # N/m (linear)
K_HERTZ = 1e9  # (4/3)E*, Pa (Hertz: stiffness K_HERTZ sqrt(r) N/m^1.5)
K_T = 2.0 / 7.0 * K_N  # N/m (linear)
K_T_HERTZ = 2.0 / 7.0 * K_HERTZ  # Pa (Hertz: stiffness K_T_HERTZ sqrt(r delta) N/m)
PHASES = (0.0, 0.37, 0.9)  # first touch at these fractions of a step: e must not depend on it


def _rotation(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def _box(width, height, x0=0.0, y0=0.0):
    """Counter-clockwise rectangle [x0 - w/2, x0 + w/2] x [y0 - h/2, y0 + h/2]."""
    hw, hh = 0.5 * width, 0.5 * height
    return np.array(
        [[x0 - hw, y0 - hh], [x0 + hw, y0 - hh], [x0 + hw, y0 + hh], [x0 - hw, y0 + hh]]
    )


class Body:
    """One polygon as a rigid body integrated by symplectic Euler (kick, then drift).

    FREE: translation and rotation about the centre of mass; PINNED: rotation about the fixed
    pivot (carrier of infinite inertia); KINEMATIC: moves at constant V, omega (0 unless set).
    ``polys`` is its one-polygon ``PolygonSet``, posed by ``set_pose``.
    """

    def __init__(self, local, com_local, kind, mass, inertia, pivot=(0.0, 0.0)):
        self.local = np.asarray(local, float)  # vertices in the body frame
        self.com_local = np.asarray(com_local, float)
        self.kind, self.mass, self.inertia = kind, mass, inertia
        self.pivot = np.asarray(pivot, float)
        self.origin = np.zeros(2)  # body-frame origin in world (FREE, KINEMATIC)
        self.theta = 0.0
        self.V = np.zeros(2)  # centre-of-mass velocity (FREE, KINEMATIC)
        self.omega = 0.0
        verts, com, _ = self.pose()
        self.polys = polygon_set(
            [verts], com[None], kind=[kind], mass=[mass], inertia=[inertia], pivot=self.pivot[None]
        )

    def pose(self):
        """World vertices, centre of mass and its velocity now."""
        rot = _rotation(self.theta)
        base = self.pivot if self.kind == PINNED else self.origin
        verts = base + self.local @ rot.T
        com = base + rot @ self.com_local
        if self.kind == PINNED:
            arm = com - self.pivot
            vel = self.omega * np.array([-arm[1], arm[0]])
        else:
            vel = self.V.copy()
        return verts, com, vel

    def set_pose(self):
        verts, com, vel = self.pose()
        self.polys.set_pose(0, verts, com, vel, self.omega)

    def move(self, F, T, dt):
        """Kick by force F (2,) and torque T about the centre of mass over dt, then drift."""
        if self.kind == FREE:
            self.V += F / self.mass * dt
            self.omega += T / self.inertia * dt
        elif self.kind == PINNED:
            _, com, _ = self.pose()
            arm = com - self.pivot
            self.omega += (T + arm[0] * F[1] - arm[1] * F[0]) / self.inertia * dt
        if self.kind != PINNED:
            self.origin += self.V * dt
        self.theta += self.omega * dt

    def surface_velocity(self, p):
        _, com, vel = self.pose()
        return vel + self.omega * np.array([-(p - com)[1], (p - com)[0]])

    def body_momenta(self):
        """Linear momentum (2,) and angular momentum about the origin (2 terms) of a FREE body."""
        _, com, _ = self.pose()
        spin = self.mass * (com[0] * self.V[1] - com[1] * self.V[0])
        return self.mass * self.V, np.array([spin, self.inertia * self.omega])

    def body_energy(self):
        if self.kind == FREE:
            return 0.5 * self.mass * self.V @ self.V + 0.5 * self.inertia * self.omega**2
        if self.kind == PINNED:
            return 0.5 * self.inertia * self.omega**2
        return 0.0


class Scene(Body):
    """One disc and one polygon body, both integrated by symplectic Euler (kick, then drift)."""

    def __init__(self, local, com_local, kind, mass, inertia, table, dt, pivot=(0.0, 0.0)):
        super().__init__(local, com_local, kind, mass, inertia, pivot)
        self.table, self.dt = table, dt
        self.x = np.zeros((1, 2))
        self.v = np.zeros((1, 2))
        self.w = np.zeros(1)
        self.hist = np.zeros((1, 1, HIST_COLUMNS))
        self.f = np.zeros((1, 2))
        self.tq = np.zeros(1)

    def forces(self):
        self.set_pose()
        self.polys.clear_loads()
        self.f[:] = 0.0
        self.tq[:] = 0.0
        return polygon_contacts(
            self.x, self.v, self.w, np.array([R]), np.array([M_DISC]), np.zeros(1, np.int32),
            self.polys, self.table, self.dt, self.hist, self.f, self.tq,
        )  # fmt: skip

    def step(self):
        n = self.forces()
        dt = self.dt
        self.v += self.f / M_DISC * dt
        self.w += self.tq / I_DISC * dt
        self.x += self.v * dt
        self.move(self.polys.force[0], self.polys.torque[0], dt)
        return n

    def momenta(self):
        """Linear momentum (2,) and angular momentum about the origin of disc + FREE polygon."""
        x, v = self.x[0], self.v[0]
        p_body, l_body = self.body_momenta()
        disc = [M_DISC * (x[0] * v[1] - x[1] * v[0]), I_DISC * self.w[0]]
        return M_DISC * v + p_body, np.concatenate([disc, l_body])

    def kinetic_energy(self):
        e = 0.5 * M_DISC * self.v[0] @ self.v[0] + 0.5 * I_DISC * self.w[0] ** 2
        return e + self.body_energy()


HAMMER_W, HAMMER_H = 0.02, 0.01  # free block, m
ARM_L = 0.1  # pinned hammer length, m; hit at 0.08 m from the pivot
HIT_ARM = 0.08


def _target(kind, mass):
    """Body geometry, inertia and its effective mass at the hit point (centre of the top face)."""
    if kind == PINNED:
        local = _box(ARM_L, HAMMER_H, x0=0.5 * ARM_L)
        com_local = np.array([0.5 * ARM_L, 0.0])
        inertia = mass * (ARM_L**2 + HAMMER_H**2) / 12.0 + mass * (0.5 * ARM_L) ** 2
        return local, com_local, inertia, inertia / HIT_ARM**2, np.array([HIT_ARM, 0.5 * HAMMER_H])
    local = _box(HAMMER_W, HAMMER_H)
    inertia = mass * (HAMMER_W**2 + HAMMER_H**2) / 12.0
    m_poly = mass if kind == FREE else math.inf
    return local, np.zeros(2), inertia, m_poly, np.array([0.0, 0.5 * HAMMER_H])


def _normal_impact(kind, mass, e, v0, law, phase, friction=0.0, v_t=0.0, fused=False, end="force"):
    """Disc falling on the top face at v0 (sliding at v_t); returns (e, energy before, after).

    fused: the disc is stepped by ``SoftGranules`` with the polygon inside its compiled step (one
    step per call, the body moved between calls from the returned loads), instead of by
    ``Scene`` around the standalone ``polygon_contacts``.
    """
    local, com_local, inertia, m_poly, hit = _target(kind, mass)
    m_eff = 1.0 / (1.0 / M_DISC + 1.0 / m_poly)
    if law == "linear":
        table = contact_table(K_N, K_T, e, friction, "linear", end)
        t_c = LinearSpringDashpot.from_stiffness(K_N, e, m_eff, end).duration
    else:
        table = contact_table(K_HERTZ, K_T_HERTZ, e, friction, "hertz", end)
        contact = HertzTsuji(K_HERTZ * math.sqrt(R), table.damping[0, 0], m_eff, end)
        t_c = contact.impact(v0).duration
    dt = t_c / 50.0
    sc = Scene(local, com_local, kind, mass, inertia, table, dt)
    sc.x[0] = hit + np.array([0.0, R + phase * v0 * dt])
    sc.v[0] = (v_t, -v0)
    energy0 = sc.kinetic_energy()
    step = _fused_stepper(sc) if fused else sc.step
    touched = False
    for _ in range(10_000):
        n = step()
        touched |= n > 0
        if touched and n == 0:
            break
    else:
        raise AssertionError("contact did not end")
    normal = _rotation(sc.theta) @ np.array([0.0, 1.0])
    p = sc.x[0] - R * normal
    v_rel_n = (sc.v[0] - sc.surface_velocity(p)) @ normal
    return v_rel_n / v0, energy0, sc.kinetic_energy()


def _fused_stepper(sc):
    """A ``Scene.step`` replacement that steps the disc with ``SoftGranules`` (polygon fused).

    Keeps sc.x, sc.v, sc.w in sync; returns 1 if the contact was evaluated, like ``step``.
    """
    row = contact_parameters("linear", 0.5, k_n=K_N)  # granule pairs: none here
    g = SoftGranules(
        sc.x, [R], [M_DISC], uniform_table(row), v=sc.v, w=sc.w, inertia=[I_DISC], dt=sc.dt,
        polygons=sc.polys, polygon_table=sc.table,
    )  # fmt: skip

    def step():
        sc.set_pose()
        g.step(1)
        sc.move(g.polygons.force[0], g.polygons.torque[0], sc.dt)
        sc.x[:], sc.v[:], sc.w[:] = g.x, g.v, g.w
        return int(g.polygon_hist[0, 0, HIST_ACTIVE])

    return step


TARGETS = [(FREE, 5e-3), (FREE, 0.2), (PINNED, 0.2), (KINEMATIC, math.inf)]
TARGET_IDS = ["free-5g", "free-200g", "pinned-200g", "kinematic"]


@pytest.mark.parametrize(("kind", "mass"), TARGETS, ids=TARGET_IDS)
@pytest.mark.parametrize("e", [0.3, 0.5, 0.6, 0.7, 0.8, 0.9])
@pytest.mark.parametrize("law", ["linear", "hertz"])
def test_restitution_on_a_face(kind, mass, e, law):
    """e from the relative normal velocity within 0.5 % at 1, 10, 30 m/s, dt = t_c/50, any phase."""
    for v0 in (1.0, 10.0, 30.0):
        for phase in PHASES:
            e_sim, energy0, energy1 = _normal_impact(kind, mass, e, v0, law, phase)
            assert e_sim == pytest.approx(e, rel=5e-3), (v0, phase)
            assert energy1 < energy0


@pytest.mark.parametrize(("kind", "mass"), TARGETS, ids=TARGET_IDS)
@pytest.mark.parametrize("law", ["linear", "hertz"])
@pytest.mark.parametrize("e", [0.3, 0.7])
def test_restitution_with_the_overlap_end(kind, mass, e, law):
    """end="overlap" (force may pull until δ = 0, damping tuned for it): e within 0.5 %."""
    for v0 in (1.0, 30.0):
        for phase in PHASES:
            e_sim, _, _ = _normal_impact(kind, mass, e, v0, law, phase, end="overlap")
            assert e_sim == pytest.approx(e, rel=5e-3), (v0, phase)


def test_overlap_end_reaches_low_restitution():
    """e = 0.1 is out of reach of a force-clamped contact (e > e⁻²) but not of "overlap": at
    t_c/50 within 1 % (the heavily damped contact's discretisation error, second order: the
    pair and wall contacts of tests/soft/test_hard_cases.py measure −0.64 % there)."""
    with pytest.raises(ValueError, match="overlap"):
        contact_table(K_N, K_T, 0.1, 0.0, "linear")
    e_sim, _, _ = _normal_impact(KINEMATIC, math.inf, 0.1, 10.0, "linear", 0.37, end="overlap")
    assert e_sim == pytest.approx(0.1, rel=1e-2)


@pytest.mark.parametrize(("kind", "mass"), TARGETS, ids=TARGET_IDS)
@pytest.mark.parametrize("law", ["linear", "hertz"])
def test_energy_never_rises(kind, mass, law):
    """Oblique hits with friction lose energy for e < 1; e = 1 keeps it to the scheme's O(dt²).

    At e = 1 (no dashpot) symplectic Euler's error at first touch and at separation, which fall
    at arbitrary times inside a step, gives |ΔE|/E up to 7e-5 at dt = t_c/50 (either sign).
    """
    for v0 in (1.0, 30.0):
        for phase in PHASES:
            for e in (0.3, 0.7, 0.999):
                _, energy0, energy1 = _normal_impact(kind, mass, e, v0, law, phase, 0.5, 0.5 * v0)
                assert energy1 < energy0
            e_sim, energy0, energy1 = _normal_impact(kind, mass, 1.0, v0, law, phase)
            assert e_sim == pytest.approx(1.0, rel=5e-3)
            assert energy1 == pytest.approx(energy0, rel=1e-4)


def _single(x, polys, table, v=None, w=None):
    """One force evaluation for discs at x (zero velocities unless given)."""
    n = x.shape[0]
    f = np.zeros((n, 2))
    tq = np.zeros(n)
    hist = np.zeros((n, polys.n_poly, HIST_COLUMNS))
    polys.clear_loads()
    count = polygon_contacts(
        np.ascontiguousarray(x, float),
        np.zeros((n, 2)) if v is None else v,
        np.zeros(n) if w is None else w,
        np.full(n, R), np.full(n, M_DISC), np.zeros(n, np.int32),
        polys, table, 1e-7, hist, f, tq,
    )  # fmt: skip
    return count, f, tq


def _hexagon(radius=0.01, centre=(0.0, 0.0), phase=0.3):
    a = phase + np.arange(6) * np.pi / 3.0
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def test_corner_contact_normal_is_along_centre_corner():
    """A disc in a corner's Voronoi region is pushed along corner -> centre with F = k δ."""
    hexagon = _hexagon()
    polys = polygon_set([hexagon], np.zeros((1, 2)), kind=[KINEMATIC])
    table = contact_table(K_N, K_T, 0.7, 0.5)
    for corner in hexagon:
        out = corner / np.linalg.norm(corner)
        for tilt in (-0.4, 0.0, 0.45):  # within the ±30° Voronoi cone of a hexagon corner
            direction = _rotation(tilt) @ out
            x = corner + 0.8 * R * direction
            count, f, _ = _single(x[None], polys, table)
            assert count == 1
            assert f[0] == pytest.approx(K_N * 0.2 * R * direction, rel=1e-9, abs=1e-9)


def test_inside_centre_uses_the_edge_of_deepest_penetration():
    """A centre inside: normal of the edge with the largest signed distance, δ = r − s."""
    box = _box(0.02, 0.01)
    polys = polygon_set([box], np.zeros((1, 2)), kind=[KINEMATIC])
    table = contact_table(K_N, K_T, 0.7, 0.5)
    cases = [  # centre, expected normal, depth below that edge
        ((0.003, 0.004), (0.0, 1.0), 0.001),
        ((0.009, 0.0), (1.0, 0.0), 0.001),
        ((-0.0085, -0.003), (-1.0, 0.0), 0.0015),
        ((0.001, -0.0042), (0.0, -1.0), 0.0008),
    ]
    for centre, normal, depth in cases:
        count, f, _ = _single(np.array([centre]), polys, table)
        assert count == 1
        assert f[0] == pytest.approx(K_N * (R + depth) * np.array(normal), rel=1e-9, abs=1e-9)


def _reference_overlap(x, verts):
    """Overlap and normal of a disc with a convex CCW polygon, by brute force (pure Python)."""
    m = len(verts)
    edges = [(verts[j], verts[(j + 1) % m]) for j in range(m)]
    signed = []
    for a, b in edges:
        e = b - a
        n = np.array([e[1], -e[0]]) / np.linalg.norm(e)
        signed.append(((x - a) @ n, n))
    s_max, n_max = max(signed, key=lambda t: t[0])
    if s_max <= 0.0:
        return R - s_max, n_max
    best = None
    for a, b in edges:
        e = b - a
        t = min(max((x - a) @ e / (e @ e), 0.0), 1.0)
        q = a + t * e
        d = np.linalg.norm(x - q)
        if best is None or d < best[0]:
            best = (d, (x - q) / d)
    return R - best[0], best[1]


def test_forces_match_brute_force_reference_with_broad_phase():
    """Random discs around two polygons: the broad phase drops no contact; F = k δ n each."""
    rng = np.random.default_rng(4)
    polys_v = [_hexagon(0.012, (0.0, 0.0), 0.1), _box(0.03, 0.006, 0.035, 0.004)]
    polys = polygon_set(polys_v, np.array([[0.0, 0.0], [0.035, 0.004]]), kind=[KINEMATIC] * 2)
    table = contact_table(K_N, K_T, 0.7, 0.5)
    x = rng.uniform([-0.02, -0.02], [0.06, 0.02], size=(3000, 2))
    count, f, tq = _single(x, polys, table)
    expected = np.zeros_like(x)
    n_expected = 0
    for i in range(len(x)):
        for verts in polys_v:
            delta, n = _reference_overlap(x[i], verts)
            if delta > 0.0:
                expected[i] += K_N * delta * n
                n_expected += 1
    assert n_expected > 200
    assert count == n_expected
    np.testing.assert_allclose(f, expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_array_equal(tq, 0.0)
    np.testing.assert_allclose(polys.force.sum(axis=0), -f.sum(axis=0), rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("law", ["linear", "hertz"])
def test_momentum_and_angular_momentum_are_conserved(law):
    """Disc + free polygon, oblique off-centre spinning hits with friction: P and L to 1e-12."""
    local = _hexagon(0.008, phase=0.2)
    mass = 5e-3
    inertia = 5.0 / 16.0 * mass * 0.008**2 * 2.0  # any positive moment will do
    if law == "linear":
        table = contact_table(K_N, K_T, 0.6, 0.4, law)
    else:
        table = contact_table(K_HERTZ, K_T_HERTZ, 0.6, 0.4, law)
    sc = Scene(local, np.zeros(2), FREE, mass, inertia, table, dt=2e-7)
    sc.origin[:] = (0.001, -0.002)
    sc.V[:] = (0.5, 0.3)
    sc.omega = 40.0
    sc.x[0] = (0.001 + 0.0035, 0.0105 + R)
    sc.v[0] = (-2.0, -12.0)
    sc.w[0] = 300.0
    p0, l0 = sc.momenta()
    p_scale = M_DISC * np.linalg.norm(sc.v[0]) + mass * np.linalg.norm(sc.V)
    energy0 = sc.kinetic_energy()
    contacts = 0
    for _ in range(4000):
        contacts += sc.step()
        p, terms = sc.momenta()
        l_scale = np.abs(terms).sum()
        assert np.all(np.abs(p - p0) <= 1e-12 * p_scale)
        assert abs(terms.sum() - l0.sum()) <= 1e-12 * l_scale
    assert contacts > 20
    assert sc.kinetic_energy() < energy0
    assert np.linalg.norm(sc.V - (0.5, 0.3)) > 0.05  # the polygon was hit


def test_sticking_spring_and_sliding_cap():
    """Tangential Cundall-Strack spring while sticking, |F_t| = f F_n while sliding; reset."""
    box = _box(0.02, 0.01)
    polys = polygon_set([box], np.zeros((1, 2)), kind=[KINEMATIC])
    f_coef = 0.4
    table = contact_table(K_N, K_T, 0.7, f_coef)
    delta = 1e-4
    x = np.array([[0.0, 0.005 + R - delta]])
    v = np.array([[1.0, 0.0]])  # sticks for 140 steps, then slides
    w = np.zeros(1)
    hist = np.zeros((1, 1, HIST_COLUMNS))
    hist[0, 0, HIST_ACTIVE] = 1.0  # a contact in progress (no onset correction)
    hist[0, 0, HIST_SLIP] = -v[0, 0]  # moving at v before (slip along t = (-1, 0))
    dt = 1e-6
    f_n = K_N * delta
    args = (np.full(1, R), np.full(1, M_DISC), np.zeros(1, np.int32), polys, table, dt, hist)
    sliding = 0
    for step in range(1, 200):
        f = np.zeros((1, 2))
        tq = np.zeros(1)
        polys.clear_loads()
        polygon_contacts(x, v, w, *args, f, tq)
        f_t_spring = -K_T * v[0, 0] * dt * step
        if abs(f_t_spring) < f_coef * f_n:
            assert f[0, 0] == pytest.approx(f_t_spring, rel=1e-12)
        else:
            sliding += 1
            assert f[0, 0] == pytest.approx(-f_coef * f_n, rel=1e-12)
        assert f[0, 1] == pytest.approx(f_n, rel=1e-12)
        assert tq[0] == pytest.approx((R - 0.5 * delta) * f[0, 0], rel=1e-12)
    assert sliding > 50
    assert hist[0, 0, HIST_XI] == pytest.approx(-f_coef * f_n / K_T, rel=1e-12)  # t = (-1, 0)
    assert hist[0, 0, HIST_NORMAL_IMPULSE] == pytest.approx(199 * f_n * dt, rel=1e-12)
    totals = hist[0, 0, HIST_NORMAL_IMPULSE:].copy()
    spring = 0.5 * K_T * hist[0, 0, HIST_XI] ** 2
    x[0, 1] += 2.0 * delta  # separate: the spring is forgotten, the contact's totals are kept
    polygon_contacts(x, v, w, *args, np.zeros((1, 2)), np.zeros(1))
    np.testing.assert_array_equal(hist[0, 0, [HIST_XI, HIST_ACTIVE, HIST_RATE, HIST_SLIP]], 0.0)
    assert hist[0, 0, HIST_NORMAL_IMPULSE] == totals[0]
    assert hist[0, 0, HIST_TANGENTIAL_IMPULSE] == totals[1]
    # The dropped spring's energy counts as dissipated.
    assert hist[0, 0, HIST_DISSIPATED] == pytest.approx(totals[2] + spring, rel=1e-12)


@pytest.mark.parametrize("law", ["linear", "hertz"])
def test_tangential_stiffness_and_stored_energy(law):
    """One step of slip v dt on a face pressed to δ: F_t = −k_t ξ with ξ = v_t dt, k_t = K_T
    (LINEAR) or K_T √(r δ) (HERTZ, Mindlin-like like the granule table's P_KT √δ: twice at 4δ;
    its history is ξ√k_t, ``laws.tangential_force``); ``contact_energy`` = normal spring energy
    + ½ k_t ξ² (round-off, 1e-12)."""
    box = _box(0.02, 0.01)
    polys = polygon_set([box], np.zeros((1, 2)), kind=[KINEMATIC])
    if law == "linear":
        table = contact_table(K_N, K_T, 0.7, 0.5)
    else:
        table = contact_table(K_HERTZ, K_T_HERTZ, 0.7, 0.5, "hertz")
    dt = 1e-7
    for delta in (1e-5, 4e-5):
        x = np.array([[0.0, 0.005 + R - delta]])
        v = np.array([[1.0, 0.0]])  # slip -1 m/s along t = (-1, 0)
        hist = np.zeros((1, 1, HIST_COLUMNS))
        hist[0, 0, HIST_ACTIVE] = 1.0
        hist[0, 0, HIST_SLIP] = -1.0
        f = np.zeros((1, 2))
        args = (np.full(1, R), np.full(1, M_DISC), np.zeros(1, np.int32), polys, table, dt, hist)
        polygon_contacts(x, v, np.zeros(1), *args, f, np.zeros(1))
        if law == "linear":
            k_t, normal = K_T, 0.5 * K_N * delta**2
        else:
            k_t = K_T_HERTZ * math.sqrt(R * delta)
            normal = 0.4 * K_HERTZ * math.sqrt(R) * delta**2.5
        assert f[0, 0] == pytest.approx(-k_t * dt, rel=1e-12)  # F_t = k_t dt along t
        history = -dt * (math.sqrt(k_t) if law == "hertz" else 1.0)
        assert hist[0, 0, HIST_XI] == pytest.approx(history, rel=1e-12)
        stored = contact_energy(x, args[0], args[2], polys, table, hist)
        assert stored == pytest.approx(normal + 0.5 * k_t * dt**2, rel=1e-12)


def test_result_does_not_depend_on_thread_count():
    rng = np.random.default_rng(1)
    polys = polygon_set([_hexagon(0.012)], np.zeros((1, 2)), kind=[FREE], mass=[0.01],
                        inertia=[1e-6])  # fmt: skip
    table = contact_table(K_N, K_T, 0.7, 0.5)
    x = rng.uniform(-0.015, 0.015, size=(5000, 2))
    v = rng.normal(size=(5000, 2))
    w = rng.normal(size=5000) * 100.0
    results = []
    threads = numba.get_num_threads()
    try:
        for n_threads in (1, 2):  # the conftest holds numba at one thread: ask for two
            numba.set_num_threads(n_threads)
            _, f, tq = _single(x, polys, table, v, w)
            results.append((f, tq, polys.force.copy(), polys.torque.copy()))
    finally:
        numba.set_num_threads(threads)
    for a, b in zip(results[0], results[1], strict=True):
        np.testing.assert_array_equal(a, b)


def test_input_checks():
    with pytest.raises(ValueError, match="counter-clockwise"):
        polygon_set([_box(0.02, 0.01)[::-1]], np.zeros((1, 2)), kind=[KINEMATIC])
    with pytest.raises(ValueError, match="convex"):
        concave = np.array([[0, 0], [2, 0], [2, 2], [1, 0.5], [0, 2]], float)
        polygon_set([concave], np.zeros((1, 2)), kind=[KINEMATIC])
    with pytest.raises(ValueError, match="FREE needs"):
        polygon_set([_box(0.02, 0.01)], np.zeros((1, 2)), kind=[FREE], mass=[0.0])
    polys = polygon_set([_box(0.02, 0.01)], np.zeros((1, 2)), kind=[KINEMATIC])
    table = contact_table(K_N, K_T, 0.7, 0.5)
    n = 2
    with pytest.raises(ValueError, match="history"):
        polygon_contacts(
            np.zeros((n, 2)), np.zeros((n, 2)), np.zeros(n), np.full(n, R), np.full(n, M_DISC),
            np.zeros(n, np.int32), polys, table, 1e-7, np.zeros((n, 1, 3)), np.zeros((n, 2)),
            np.zeros(n),
        )  # fmt: skip
