"""Polygons inside the compiled step (``SoftGranules(polygons=..., polygon_table=...)``): the same
contact as the standalone ``polygon_contacts``, rigid motion of the polygons within a call, mean
loads, impact history, candidate list, thread count."""

import math

import numba
import numpy as np
import pytest

from perga.analytic.contact import HertzTsuji, LinearSpringDashpot
from perga.contact.soft import SoftGranules, chamber, contact_parameters, uniform_table
from perga.contact.soft.kernel import (
    COUNT_CONTACT_CHANGES,
    COUNT_RELEASES,
    DISSIPATED_PAIRS,
    DISSIPATED_POLYGONS,
)
from perga.contact.soft.polygon_forces import candidate_reach, candidates
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_ACTIVE,
    HIST_COLUMNS,
    HIST_DISSIPATED,
    HIST_NORMAL_IMPULSE,
    HIST_TANGENTIAL_IMPULSE,
    KINEMATIC,
    PINNED,
    contact_table,
    polygon_set,
)
from perga.geometry.disc_polygon import bounding_radii, closest_feature, separation

from .marks import TWO_THREADS
from .test_polygons import (
    I_DISC,
    K_HERTZ,
    K_N,
    K_T,
    K_T_HERTZ,
    M_DISC,
    PHASES,
    TARGET_IDS,
    TARGETS,
    Body,
    R,
    _box,
    _hexagon,
    _normal_impact,
    _rotation,
)

PAIR_ROW = contact_parameters("linear", 0.7, k_n=K_N, friction=0.5)


def _granules(x, v, polys, table, dt, w=None, **options):
    """Discs of radius R and mass M_DISC at x with velocities v around the polygons ``polys``."""
    n = len(x)
    return SoftGranules(
        x, np.full(n, R), np.full(n, M_DISC), uniform_table(PAIR_ROW), v=v, w=w,
        inertia=np.full(n, I_DISC), dt=dt, polygons=polys, polygon_table=table, **options,
    )  # fmt: skip


def _linear(e, friction=0.0):
    """Linear granule-polygon table and dt = t_c/50 of a disc on an immovable face."""
    t_c = LinearSpringDashpot.from_stiffness(K_N, e, M_DISC, "force").duration
    return contact_table(K_N, K_T, e, friction), t_c / 50.0


@pytest.mark.parametrize(("kind", "mass"), TARGETS, ids=TARGET_IDS)
@pytest.mark.parametrize("law", ["linear", "hertz"])
def test_fused_restitution_equals_standalone(kind, mass, law):
    """One step per call, the body moved between calls: e as the standalone path's.

    Same arithmetic in both paths, so the two e agree to round-off (measured 7e-14 relative;
    asserted 1e-12), and both are within the restitution tolerance of 0.5 % at dt = t_c/50.
    """
    for e in (0.3, 0.7, 0.9):
        for v0 in (1.0, 30.0):
            for phase in PHASES:
                e_alone, _, _ = _normal_impact(kind, mass, e, v0, law, phase)
                e_fused, energy0, energy1 = _normal_impact(
                    kind, mass, e, v0, law, phase, fused=True
                )
                assert e_fused == pytest.approx(e, rel=5e-3), (e, v0, phase)
                assert e_fused == pytest.approx(e_alone, rel=1e-12)
                assert energy1 < energy0


@pytest.mark.parametrize("law", ["linear", "hertz"])
@pytest.mark.parametrize("e", [0.3, 0.7, 0.9])
def test_moving_face_launches_a_resting_disc(law, e):
    """A kinematic face moving at V hits a disc at rest: it leaves at (1 + e) V.

    Calls of 20 steps: the face only reaches the disc by its rigid motion within the calls
    (the caller never re-poses it). Tolerance 0.5 % (the restitution tolerance), dt = t_c/50.
    """
    speed = 5.0
    if law == "linear":
        table, dt = _linear(e)
    else:
        table = contact_table(K_HERTZ, K_T_HERTZ, e, 0.0, "hertz")
        t_c = HertzTsuji(K_HERTZ * math.sqrt(R), table.damping[0, 0], M_DISC, "force")
        dt = t_c.impact(speed).duration / 50.0
    polys = polygon_set(
        [_box(0.02, 0.01)], np.zeros((1, 2)), kind=[KINEMATIC], velocity=np.array([[0.0, speed]])
    )
    g = _granules([[0.001, 0.005 + R + 0.37 * speed * dt + 3e-4]], [[0.0, 0.0]], polys, table, dt)
    for _ in range(1000):
        g.step(20)
        if g.v[0, 1] > 0.0 and g.polygon_hist[0, 0, HIST_ACTIVE] == 0.0:
            break
    assert g.v[0, 1] == pytest.approx((1.0 + e) * speed, rel=5e-3)
    assert abs(g.v[0, 0]) <= 1e-12 * speed  # round-off of the face normal
    np.testing.assert_allclose(polys.com[0], [0.0, g.time * speed], rtol=1e-12)


def test_poses_within_a_call_are_rigid_motion():
    """A kinematic hexagon translating and turning through discs, with a PINNED-style pivot.

    Calls of 37 steps give the trajectories of calls of one step in which the test poses the
    body itself by the closed form (com + V t, vertices turned by ω t about com), so the pose at
    every step inside a call is that rigid motion: to round-off of the poses (~1e-18 m) grown by
    the collisions over 2,220 steps (measured 1e-9 relative in the contact totals, asserted
    1e-8). After each call the set holds the closed-form pose at the granules' time (pivot
    included) to 1e-15 m.
    """
    table, dt = _linear(0.6, friction=0.4)
    local = _hexagon(0.008)
    x = _lattice(-0.02, 0.02, -0.02, 0.02, 2.1 * R)
    x = x[[_distance(p, local) > 1.1 * R for p in x]]
    velocity, omega = np.array([3.0, -1.0]), 400.0
    pivot = np.array([0.004, 0.001])

    def run(steps_per_call):
        body = Body(local, np.zeros(2), KINEMATIC, math.inf, math.inf, pivot)
        body.V[:] = velocity
        body.omega = omega
        body.set_pose()
        body.polys.pivot[0] = pivot
        g = _granules(x, np.zeros_like(x), body.polys, table, dt)
        for _ in range(60):
            if steps_per_call == 1:
                for _ in range(37):
                    body.set_pose()
                    g.step(1)
                    body.move(np.zeros(2), 0.0, dt)
            else:
                g.step(37)
            t = g.time
            np.testing.assert_allclose(g.polygons.com[0], velocity * t, rtol=0, atol=1e-15)
            rotated = local @ _rotation(omega * t).T + velocity * t
            np.testing.assert_allclose(g.polygons.vertices, rotated, rtol=0, atol=1e-15)
            arm = _rotation(omega * t) @ pivot
            np.testing.assert_allclose(g.polygons.pivot[0], arm + velocity * t, atol=1e-15)
        return g

    one, fused = run(1), run(37)
    assert np.count_nonzero(fused.polygon_hist[:, 0, HIST_NORMAL_IMPULSE]) >= 3
    np.testing.assert_allclose(fused.x, one.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fused.v, one.v, rtol=1e-8, atol=1e-9)
    np.testing.assert_allclose(fused.polygon_hist, one.polygon_hist, rtol=1e-8, atol=1e-15)


@pytest.mark.parametrize("kind", [FREE, PINNED], ids=["free", "pinned"])
def test_a_body_recoils_within_a_call_as_between_calls_of_one_step(kind):
    """Four discs hit a light hexagon (5 g; pinned 4 mm off its centre) with friction and spin.

    Calls of 10 steps, in which the kernel kicks the body by each step's loads (and after
    which the test kicks it by the call's mean loads, as the machine step does), give the
    trajectories of calls of one step between which the test kicks and moves the body itself
    (``Body.move``: symplectic Euler, FREE about its centre, PINNED about a fixed pivot).
    FREE: the same symplectic Euler steps of the body, so they agree to round-off grown by the
    collisions over 3,000 steps (measured 2e-17 m, 3e-13 m/s; asserted 1e-12 m, 1e-9 m/s).
    PINNED: within a call the kernel moves the body along a straight line between kicks,
    ½ (ω dt)² d off its circle a step where the test turns it about A (ω up to 100 rad/s,
    d = 4 mm): measured 1.8e-8 m, 1.1e-5 m/s; asserted 1e-7 m, 1e-4 m/s. With the body at its
    call-start velocities through a call (no kicks inside it) the granules were off by 0.15-0.16
    mm and 0.07-0.1 m/s.
    """
    table, dt = _linear(0.6, friction=0.4)
    mass, inertia = 5e-3, 2e-7
    pivot = np.array([0.0, 0.0]) if kind == FREE else np.array([-0.004, 0.0])
    x = np.array([[0.0045, 0.0105 + R], [-0.012, 0.0], [0.003, -0.013], [0.0125, -0.004]])
    v = np.array([[-2.0, -12.0], [9.0, 1.0], [0.0, 8.0], [-6.0, 3.0]])
    w = np.array([300.0, -200.0, 0.0, 50.0])
    moment = inertia if kind == FREE else inertia + mass * 0.004**2

    def run(steps_per_call: int) -> SoftGranules:
        body = Body(_hexagon(0.008) - pivot, -pivot, kind, mass, moment, pivot)  # centred at 0
        body.V[:] = (0.5, 0.3) if kind == FREE else (0.0, 0.0)
        body.omega = 40.0
        body.set_pose()
        g = _granules(x, v, body.polys, table, dt, w=w)
        for _ in range(3000 // steps_per_call):
            if steps_per_call == 1:
                g.step(1)
                body.move(body.polys.force[0], body.polys.torque[0], dt)
                body.set_pose()
            else:
                _kick_after_call(g, steps_per_call, dt, pivot)
        return g

    one, fused = run(1), run(10)
    assert np.count_nonzero(fused.polygon_hist[:, 0, HIST_NORMAL_IMPULSE]) == 4  # all four hit
    position, speed = (1e-12, 1e-9) if kind == FREE else (1e-7, 1e-4)
    np.testing.assert_allclose(fused.x, one.x, rtol=0, atol=position)
    np.testing.assert_allclose(fused.v, one.v, rtol=0, atol=speed)


def _kick_after_call(g: SoftGranules, n: int, dt: float, pivot: np.ndarray) -> None:
    """One call of n steps, then the body kicked by the call's impulses, as the machine step
    kicks a hammer: FREE by the mean force and torque about its centre; PINNED at the fixed
    ``pivot`` A by the mean moment about A, M̄_O − A × F̄ (exact for a pivot at rest), and put
    back on its circle about A (as the hinge joint does: within a call the kernel moves it
    along a straight line, ½ (ω n dt)² d off the circle)."""
    p = g.polygons
    g.step(n)
    force = p.force[0] * n * dt
    if p.kind[0] == FREE:
        p.velocity[0] += force / p.mass[0]
        p.omega[0] += p.torque[0] * n * dt / p.inertia[0]
        return
    about_pivot = p.moment[0] * n * dt - (pivot[0] * force[1] - pivot[1] * force[0])
    p.omega[0] += about_pivot / p.inertia[0]
    arm = p.com[0] - pivot
    off = arm * (np.hypot(*(p.com[0] - p.pivot[0])) / np.hypot(*arm) - 1.0)
    p.vertices += off
    p.com[0] += off
    p.pivot[0] = pivot
    arm = p.com[0] - pivot
    p.velocity[0] = p.omega[0] * np.array([-arm[1], arm[0]])


def _momenta(g, body_mass, body_inertia):
    """Linear momentum (2,) and the terms of the angular momentum about the origin."""
    p = g.polygons
    com, vel = p.com[0], p.velocity[0]
    lin = (g.m[:, None] * g.v).sum(axis=0) + body_mass * vel
    terms = np.concatenate(
        [
            g.m * (g.x[:, 0] * g.v[:, 1] - g.x[:, 1] * g.v[:, 0]),
            g.inertia * g.w,
            [body_mass * (com[0] * vel[1] - com[1] * vel[0]), body_inertia * p.omega[0]],
        ]
    )
    return lin, terms


def test_momentum_is_conserved_with_a_free_polygon_moved_by_the_mean_loads():
    """Discs hit a FREE hexagon off-centre with friction and spin, calls of 10 steps.

    Inside a call the kernel kicks the body at every step (it recoils) and hands back its
    velocities as they were, its pose where the kicks took it. After each call the test kicks
    the body with the call's impulses, ΔV = F̄ n dt/M and I_c Δω = τ̄_c n dt (τ̄_c the mean
    torque about the centre of mass of each step): the granules received the opposite impulses
    at the same points, so linear and angular momentum about the origin are conserved to
    round-off (1e-12 of their scales). The body did recoil: its pose is not the one its start
    velocities would give (the in-call kicks moved it by more than 1e-9 m).
    """
    table, dt = _linear(0.6, friction=0.4)
    mass, inertia = 5e-3, 2e-7
    polys = polygon_set(
        [_hexagon(0.008, centre=(0.001, -0.002))], np.array([[0.001, -0.002]]), kind=[FREE],
        mass=[mass], inertia=[inertia], velocity=np.array([[0.5, 0.3]]), omega=np.array([40.0]),
    )  # fmt: skip
    x = np.array([[0.0045, 0.0105 + R], [-0.012, 0.0], [0.003, -0.013], [0.0125, -0.004]])
    v = np.array([[-2.0, -12.0], [9.0, 1.0], [0.0, 8.0], [-6.0, 3.0]])
    g = _granules(x, v, polys, table, dt, w=np.array([300.0, -200.0, 0.0, 50.0]))
    p0, l0 = _momenta(g, mass, inertia)
    p_scale = np.abs(g.m[:, None] * g.v).sum() + mass * np.linalg.norm(polys.velocity[0])
    recoiled = 0.0
    n = 10
    for _ in range(300):
        unkicked = polys.com[0] + polys.velocity[0] * n * dt
        g.step(n)
        recoiled = max(recoiled, float(np.abs(polys.com[0] - unkicked).max()))
        polys.velocity[0] += polys.force[0] * n * dt / mass
        polys.omega[0] += polys.torque[0] * n * dt / inertia
        p, terms = _momenta(g, mass, inertia)
        assert np.all(np.abs(p - p0) <= 1e-12 * p_scale)
        assert abs(terms.sum() - l0.sum()) <= 1e-12 * np.abs(terms).sum()
    assert np.count_nonzero(g.polygon_hist[:, 0, HIST_NORMAL_IMPULSE]) == 4  # all four hit
    assert recoiled > 1e-9


def _drop(table, dt, v0, v_t=0.0, w=0.0):
    """A disc falling at v0 (sliding at v_t) onto the top face of a kinematic box at rest."""
    polys = polygon_set([_box(0.02, 0.01)], np.zeros((1, 2)), kind=[KINEMATIC])
    x = [[0.0, 0.005 + R + 0.37 * v0 * dt]]
    return _granules(x, [[v_t, -v0]], polys, table, dt, w=[w])


def _until_separated(g, steps_per_call=7):
    touched = False
    for _ in range(10_000):
        g.step(steps_per_call)
        active = g.polygon_hist[0, 0, HIST_ACTIVE] != 0.0
        touched |= active
        if touched and not active:
            return
    raise AssertionError("contact did not end")


@pytest.mark.parametrize("e", [0.3, 0.7, 0.9])
def test_impact_history_of_a_head_on_hit(e):
    """Totals of a finished impact: normal impulse m v0 (1 + e), dissipation ½ m v0² (1 − e²).

    e is the simulated one; the impulse is the disc's momentum change, exact to round-off
    (1e-12); the dissipation comes from the contact law and differs from the kinetic energy lost
    by the O(dt²) error of the rates at the force time: ≤ 1.45e-3 ½ m v0² measured at t_c/50
    (e = 0.3), asserted 2e-3 (``test_restitution.test_dissipation_equals_kinetic_energy_lost``
    shows the order). The totals stay after the contact ends and restart at the next one.
    """
    table, dt = _linear(e, friction=0.5)
    v0 = 3.0
    g = _drop(table, dt, v0)
    _until_separated(g)
    e_sim = g.v[0, 1] / v0
    assert e_sim == pytest.approx(e, rel=5e-3)
    row = g.polygon_hist[0, 0]
    assert row[HIST_NORMAL_IMPULSE] == pytest.approx(M_DISC * v0 * (1.0 + e_sim), rel=1e-12)
    assert row[HIST_TANGENTIAL_IMPULSE] == 0.0
    lost = 0.5 * M_DISC * v0**2 * (1.0 - e_sim**2)
    assert abs(row[HIST_DISSIPATED] - lost) <= 2e-3 * 0.5 * M_DISC * v0**2
    assert g.dissipated[DISSIPATED_POLYGONS] == row[HIST_DISSIPATED]
    totals = row[HIST_NORMAL_IMPULSE:].copy()
    g.step(50)
    np.testing.assert_array_equal(g.polygon_hist[0, 0, HIST_NORMAL_IMPULSE:], totals)
    g.v[0] = (0.0, -1.0)  # send it back: the next contact starts from zero
    _until_separated(g)
    assert row[HIST_NORMAL_IMPULSE] == pytest.approx(M_DISC * (1.0 + g.v[0, 1]), rel=1e-12)


def test_tangential_impulse_of_a_sliding_hit():
    """Oblique hit in gross sliding: the tangential impulse is the disc's momentum change along
    the tangent t = (−1, 0) (round-off) and f times the normal impulse but for the few steps the
    spring takes to reach the Coulomb cap (1 %)."""
    friction = 0.3
    table, dt = _linear(0.7, friction)
    g = _drop(table, dt, 3.0, v_t=6.0)
    _until_separated(g)
    row = g.polygon_hist[0, 0]
    assert row[HIST_TANGENTIAL_IMPULSE] == pytest.approx(-M_DISC * (g.v[0, 0] - 6.0), rel=1e-12)
    assert row[HIST_TANGENTIAL_IMPULSE] == pytest.approx(friction * row[HIST_NORMAL_IMPULSE], 1e-2)


def _distance(point, vertices):
    """Distance of ``point`` from the convex polygon ``vertices`` (< 0 inside), m."""
    arrays = polygon_set([vertices], np.zeros((1, 2)), kind=[KINEMATIC]).outline()
    return closest_feature(point[0], point[1], *arrays, 0)[0]


def _lattice(x0, x1, y0, y1, pitch):
    """Hexagonal lattice of points in [x0, x1] × [y0, y1] with the given pitch, m."""
    rows = np.arange(y0, y1, pitch * math.sqrt(3.0) / 2.0)
    return np.array(
        [
            (x, y)
            for k, y in enumerate(rows)
            for x in np.arange(x0 + 0.5 * pitch * (k % 2), x1, pitch)
        ]
    )


def test_every_overlap_is_a_contact_with_a_fast_polygon():
    """A plate stirring a bed of discs in a chamber (tips at 7.5 m/s, centre drifting at 2 m/s),
    calls of 40 steps (the candidate list is built once per call and after every neighbour-list
    rebuild).

    After each call every disc overlapping the plate by more than one step's approach
    dt (|v_i| + |V| + |ω| ρ) has an active contact (none was left out of the candidates), and
    the plate hit many discs."""
    table, dt = _linear(0.7, friction=0.5)
    length, width = 0.03, 0.004
    plate = _box(length, width)
    x = _lattice(-0.03, 0.03, -0.03, 0.03, 2.1 * R)
    x = x[np.hypot(*x.T) < 0.03 - 1.1 * R]
    x = x[[_distance(p, plate) > 1.1 * R for p in x]]
    speed, omega = 2.0, 500.0
    polys = polygon_set(
        [plate], np.zeros((1, 2)), kind=[KINEMATIC], velocity=np.array([[speed, 0.0]]),
        omega=np.array([omega]),
    )  # fmt: skip
    g = _granules(x, np.zeros_like(x), polys, table, dt, walls=[chamber(0.03)])
    rho = 0.5 * math.hypot(length, width)
    checked = 0
    for _ in range(100):
        g.step(40)
        d = np.array([closest_feature(p[0], p[1], *polys.outline(), 0)[0] for p in g.x])
        approach = dt * (np.hypot(*g.v.T) + speed + abs(omega) * rho)
        deep = R - d > approach
        assert np.all(g.polygon_hist[deep, 0, HIST_ACTIVE] == 1.0)
        checked += np.count_nonzero(deep)
    assert checked > 30


def test_candidate_list_holds_exactly_the_pairs_its_rule_lets_in():
    """``candidates`` against the rule of its doc, pair by pair in plain Python: a pair is in
    when its contact is active, when the polygon turns so fast that 1 − ½ dt|ω| ≤ 0, or when
    both lower bounds of the gap from x_ref (the bounding circle's and the edge lines') are
    below r_i + reach/(1 − ½ dt|ω|). 300 discs strewn over and around three polygons (one
    spinning past that limit), a fifth of the pairs flagged active wherever they are (the far
    ones test that no active contact is left unevaluated). The lists are compared exactly:
    every entry and the order, granule then polygon."""
    rng = np.random.default_rng(7)
    shapes = [_box(0.03, 0.004), _hexagon(0.008, (0.02, 0.01)), _box(0.01, 0.01, -0.02, 0.0)]
    dt, skin, span = 1e-6, 0.4 * R, 5e-6
    velocity = np.array([[2.0, 0.0], [0.0, -1.0], [0.0, 0.0]])
    omega = np.array([500.0, -200.0, 3e6])  # the last: 1 - dt|ω|/2 < 0
    polys = polygon_set(
        shapes, np.array([s.mean(axis=0) for s in shapes]), kind=[KINEMATIC] * 3,
        velocity=velocity, omega=omega,
    )  # fmt: skip
    poly = polys.arrays()
    x = rng.uniform(-0.05, 0.05, (300, 2))
    r = np.full(300, R)
    hist = np.zeros((300, 3, HIST_COLUMNS))
    hist[:, :, HIST_ACTIVE] = rng.random((300, 3)) < 0.2
    rho = bounding_radii(poly.vertices, poly.start, poly.com)
    reach = np.empty(3)
    candidate_reach(poly, rho, span, skin, dt, reach)
    start, listed = candidates(x, r, poly, rho, hist, reach)
    expected = []
    for i in range(300):
        for k in range(3):
            top = np.hypot(*velocity[k]) + abs(omega[k]) * rho[k]
            slack = 1.0 - 0.5 * dt * abs(omega[k])
            limit = r[i] + (0.5 * skin + top * (span + 0.5 * dt)) / max(slack, 1e-300)
            near = np.hypot(*(x[i] - poly.com[k])) - rho[k] < limit and (
                separation(x[i, 0], x[i, 1], poly.vertices, poly.start[k], poly.start[k + 1])
                < limit
            )
            if hist[i, k, HIST_ACTIVE] or slack <= 0.0 or near:
                expected.append((i, k))
    got = [(i, int(k)) for i in range(300) for k in listed[start[i] : start[i + 1]]]
    assert got == expected
    far_active = sum(
        1 for i, k in expected if hist[i, k, HIST_ACTIVE] and k < 2 and np.hypot(*x[i]) > 0.045
    )
    assert far_active > 5 and len(expected) < 0.6 * 900


def test_counts_follow_the_contact_flags_and_the_releases():
    """``SoftGranules.counts``: in calls of one step (a flag can change at most once), the
    contact count grows by the number of HIST_ACTIVE flags that changed: a disc bouncing on a
    plate, one held pressed into it, one held above it struck by a fourth that breaks its bond
    and drives it onto the plate; the release count by the bonds that broke; ``relax`` counts the
    flags it clears. Exact: they are counts."""
    table, dt = _linear(0.6, friction=0.3)
    top = 0.002  # the plate's upper face
    polys = polygon_set([_box(0.06, 2 * top)], np.zeros((1, 2)), kind=[KINEMATIC])
    x = np.array(
        [[0.015, top + R + 5e-4], [-0.015, top + R - 1e-6], [0.0, top + R + 5e-4],
         [0.0, top + 3 * R + 8e-4]]
    )  # fmt: skip
    v = np.array([[0.0, -1.0], [0.0, 0.0], [0.0, 0.0], [0.0, -1.0]])
    g = _granules(x, v, polys, table, dt, gravity=(0.0, -9.81))
    g.held[1:3] = 1
    g.bond_force[2] = 0.1
    changes = 0
    for _ in range(3000):
        before = g.polygon_hist[:, :, HIST_ACTIVE].copy()
        g.step(1)
        changes += np.count_nonzero(before != g.polygon_hist[:, :, HIST_ACTIVE])
        assert g.counts[COUNT_CONTACT_CHANGES] == changes
    assert changes >= 4  # the bouncing disc met the plate and left it, the released one met it
    assert g.counts[COUNT_RELEASES] == np.count_nonzero(g.released_step >= 0) == 1
    active = np.count_nonzero(g.polygon_hist[:, :, HIST_ACTIVE])
    assert active >= 1  # the disc held pressed into the plate
    g.relax()
    assert g.counts[COUNT_CONTACT_CHANGES] == changes + active


@TWO_THREADS
def test_one_and_two_threads_give_identical_results():
    """Discs on a ring fall onto a turning FREE hexagon (moved between calls of 10 steps); they
    do not touch each other. Granule forces, polygon loads and history are summed in an order
    that does not depend on the thread count: both runs agree bit for bit."""
    table, dt = _linear(0.6, friction=0.4)
    angles = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
    ring = 0.0085 + R
    x = ring * np.column_stack([np.cos(angles), np.sin(angles)])
    v = -4.0 * x / ring + 0.5 * np.column_stack([-np.sin(angles), np.cos(angles)])

    def run(threads):
        polys = polygon_set(
            [_hexagon(0.008)], np.zeros((1, 2)), kind=[FREE], mass=[0.01], inertia=[3e-7],
            omega=np.array([300.0]),
        )  # fmt: skip
        g = _granules(x, v, polys, table, dt, threads=threads)
        loads = []
        for _ in range(60):
            g.step(10)
            polys.velocity[0] += polys.force[0] * 10 * dt / 0.01
            polys.omega[0] += polys.torque[0] * 10 * dt / 3e-7
            loads.append(np.concatenate([polys.force[0], [polys.torque[0], polys.moment[0]]]))
        return g, np.array(loads)

    previous = numba.get_num_threads()
    try:
        (a, loads_a), (b, loads_b) = run(1), run(2)
    finally:
        numba.set_num_threads(previous)
    assert np.count_nonzero(a.polygon_hist[:, 0, HIST_NORMAL_IMPULSE]) == 8
    assert a.dissipated[DISSIPATED_PAIRS] == 0.0
    for name in ("x", "v", "w", "polygon_hist", "dissipated"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    np.testing.assert_array_equal(loads_a, loads_b)


@pytest.mark.parametrize("kind", [FREE, PINNED, KINEMATIC])
def test_default_step_resolves_polygon_contacts(kind):
    """Without an explicit dt the step is t_c/50 of the shortest contact, polygons included:
    a disc on a light FREE plate (m_eff below the disc-disc m/2) sets it."""
    table = contact_table(4.0 * K_N, K_T, 0.7, 0.5)
    polys = polygon_set(
        [_box(0.002, 0.001)], np.zeros((1, 2)), kind=[kind], mass=[1e-5], inertia=[1e-12],
        pivot=np.array([[0.001, 0.0]]),
    )  # fmt: skip
    g = SoftGranules(
        [[0.0, 0.01]], [R], [M_DISC], uniform_table(PAIR_ROW), polygons=polys, polygon_table=table
    )
    pair = LinearSpringDashpot(K_N, 0.5 * PAIR_ROW[1], 0.5 * M_DISC, "force").duration
    disc_on_face = LinearSpringDashpot.from_stiffness(4.0 * K_N, 0.7, M_DISC, "force").duration
    if kind == KINEMATIC:
        assert g.t_c == pytest.approx(disc_on_face, rel=1e-12)
    else:
        assert g.t_c < min(pair, disc_on_face)
    assert g.dt == pytest.approx(g.t_c / 50.0, rel=1e-12)


def _plate_and_row() -> SoftGranules:
    """A kinematic plate 4 mm × 20 mm spinning slowly as it slides at 2 m/s towards a row of ten
    discs 10-37 mm ahead of it."""
    table, dt = _linear(0.7, friction=0.5)
    polys = polygon_set(
        [_box(0.004, 0.02, -0.01, 0.0)], np.array([[-0.01, 0.0]]), kind=[KINEMATIC],
        velocity=np.array([[2.0, 0.0]]), omega=np.array([5.0]),
    )  # fmt: skip
    x = np.column_stack([0.01 + 3.0 * R * np.arange(10), np.zeros(10)])
    return _granules(x, np.zeros_like(x), polys, table, dt)


def _jump_to(g: SoftGranules, row: int) -> None:
    """Move the plate along x, by hand, until its front is 0.1 R into disc ``row``."""
    p = g.polygons
    move = np.array([g.x[row, 0] - 0.9 * R - p.vertices[:, 0].max(), 0.0])
    p.set_pose(0, p.vertices + move, p.com[0] + move, p.velocity[0], p.omega[0])


def _against_fresh(kept: SoftGranules, fresh: SoftGranules, calls: int, changes) -> None:
    """``calls`` calls of 5 steps of ``kept`` and of ``fresh``, which drops its candidate list
    before every call (so builds it afresh, with the rule of ``candidates``); changes[c] is
    applied to both before call c. Then the two must agree bit for bit."""
    for call in range(calls):
        if call in changes:
            for g in (kept, fresh):
                changes[call](g)
        fresh._forget_candidates()
        kept.step(5)
        fresh.step(5)
    for name in ("x", "v", "w", "polygon_hist"):
        np.testing.assert_array_equal(getattr(kept, name), getattr(fresh, name), err_msg=name)


def test_a_kept_candidate_list_gives_the_floats_of_a_fresh_one():
    """Calls of 5 steps against a twin that builds its list afresh (``_against_fresh``). Midway
    the plate jumps by hand to 0.1 R into the first disc, which no list held: the kept list no
    longer holds (the plate moved through its margin) and must be rebuilt, so that the strike
    happens in both. The two agree bit for bit, and the kept list was built for far fewer calls
    than the twin's."""
    kept, fresh = _plate_and_row(), _plate_and_row()
    calls = 60
    _against_fresh(kept, fresh, calls, {30: lambda g: _jump_to(g, 0)})
    assert kept.polygon_hist[0, 0, HIST_NORMAL_IMPULSE] > 0.0  # the jump struck the first disc
    np.testing.assert_array_equal(kept.polygons.force, fresh.polygons.force)
    assert fresh.n_candidate_lists >= calls  # and one after each rebuild within a call
    assert kept.n_candidate_lists <= calls // 5, kept.n_candidate_lists


def _swap_first_for_far(g: SoftGranules) -> None:
    """Take the first disc out and add one far away: the count stays, the rows move up."""
    g.remove([0])
    g.add([[0.0, 0.05]], [R], [M_DISC], mat=[0], inertia=[I_DISC])


def test_a_kept_candidate_list_is_dropped_when_granules_are_taken_out_or_added():
    """The plate of ``_plate_and_row`` moved onto the fourth disc; after two calls the first
    disc is taken out and another added far away (the count stays ten, the rows move up by
    one). A list kept across that would pair the plate with the wrong rows; the run must equal
    bit for bit a twin that builds its list afresh before every call."""
    kept, fresh = _plate_and_row(), _plate_and_row()
    _against_fresh(kept, fresh, 6, {0: lambda g: _jump_to(g, 3), 2: _swap_first_for_far})
    assert kept.polygon_hist[2, 0, HIST_NORMAL_IMPULSE] > 0.0  # the struck disc, now row 2


def _move_into_plate_and_read(g: SoftGranules) -> None:
    """Disc 5 moved by hand 0.1 R into the plate, ``invalidate``, then ``max_overlap``, which
    rebuilds the neighbour list outside the kernel."""
    g.x[5] = (g.polygons.vertices[:, 0].max() + 0.9 * R, 0.0)
    g.invalidate()
    g.max_overlap()


def test_a_kept_candidate_list_is_dropped_when_a_diagnostic_rebuilds_the_neighbour_list():
    """A disc of ``_plate_and_row`` moved by hand into the plate and the overlaps read
    (``_move_into_plate_and_read``): the next calls must not keep a list built around the old
    reference positions. Bit for bit as a twin that builds its list afresh before every
    call."""
    kept, fresh = _plate_and_row(), _plate_and_row()
    _against_fresh(kept, fresh, 6, {2: _move_into_plate_and_read})
    assert kept.polygon_hist[5, 0, HIST_NORMAL_IMPULSE] > 0.0  # the moved disc was struck
