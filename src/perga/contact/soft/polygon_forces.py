"""Soft contacts between granules (discs) and convex polygons (:mod:`perga.contact.soft.
polygon_set`), compiled (numba), SI units.

Two ways in: ``polygon_contacts`` evaluates all contacts once at the given poses (one force
evaluation, loads added to ``PolygonSet.force``/``torque``/``moment``); ``SoftGranules`` with
polygons evaluates them inside its compiled step (``kernel.advance``), moving each polygon
rigidly with its velocities during a call (``pose``) and returning the mean loads. Both call
``polygon_contact``, the one implementation of a granule-polygon contact.

Contact geometry: the closest solid feature of the polygon (an edge or an owned corner) to the
disc centre (:func:`perga.geometry.disc_polygon.closest_feature`): outside, the normal from the
closest boundary point; inside, the outward normal of the edge of deepest penetration, overlap
δ = r − s. The force acts at the middle of the overlap, p = x − (r − δ⁺/2) n (the disc's surface
point while δ ≤ 0), with the contact's effective mass m_eff = 1/(1/m_i + 1/m_p).

Contact law: ``perga.contact.soft.laws.contact_force``, the same law (and the same time
discretisation and dissipation) as granule pairs and walls, clamped at zero (``end="force"``,
the default of ``contact_table``) or not (``end="overlap"``: max(0, ·) below is dropped and the
damping tuned for it):

* ``LINEAR``: F_n = max(0, k_n δ + 2ζ√(k_n m_eff) δ̇), ζ = ``damping_ratio(e, end)``;
  tangential stiffness k_t;
* ``HERTZ``: F_n = max(0, k δ^{3/2} + α√(m_eff k) δ^{1/4} δ̇), k = k_n √r_i (k_n = (4/3) E*,
  Pa, with R_eff = r_i for a flat face), α = ``tsuji_alpha(e, end)``; tangential stiffness
  k_t √(r_i δ) (Mindlin-like, as the k_t = P_KT √δ of the granule table's Hertz rows).

A contact is evaluated whenever ``laws.touching`` (δ > 0 somewhere in the kick interval
[t − dt/2, t + dt/2], so possibly half a step before first touch), and the dashpot enters as its
exact impulse over the overlapping part of that interval (see ``contact_force``). The approach
and slip rates handed to the law are extrapolated to the force time: the caller's velocities are
half a step old (kick, then drift), and a polygon's acceleration is not known here, so each rate
u is extrapolated from its last two half-step values, 1.5 u_{n−1/2} − 0.5 u_{n−3/2} (u_{n−1/2}
unchanged at the first evaluation of a contact, before any contact force acted; exact for a
contact at rest). This equals u + ½ dt u̇ of the previous step, i.e. the granule kernel's
extrapolation.

Tangential force: Cundall-Strack spring F_t = −k_t ξ on the accumulated tangential displacement ξ
(a scalar per (granule, polygon) pair in 2-D, along t = (−n_y, n_x)), capped at f·F_n (ξ is
rescaled so that k_t|ξ| = f F_n while sliding), no tangential damping.

Loads: the equal and opposite force on the polygon, its torque about the polygon's centre of
mass and its moment about the world origin (the rotor axis). Both sides use the same force at
the same point, so linear and angular momentum are conserved to round-off.

Broad phase: a granule is skipped for a polygon when its centre is farther than r_i plus half a
step's largest possible approach from the polygon's bounding circle (centre at the centre of mass,
radius ``bounding_radii``: invariant under the polygon's rigid motion). The fused step also keeps
a candidate list (``candidates``) so that granules far from every polygon cost nothing per step.
Granules are processed in parallel; per-polygon sums are reduced in a fixed order, so the result
does not depend on the number of threads.

Limits: a disc whose centre crosses the middle of a thin polygon in one step is pushed out of the
other side (tunnelling: see ``perga.analytic.contact.tunnelling_time_step``); rolling resistance
is not modelled.
"""

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from perga.contact.laws.row import LINEAR
from perga.contact.soft.laws import contact_force, spring_energy, touching
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_ACTIVE,
    HIST_COLUMNS,
    HIST_DISSIPATED,
    HIST_NORMAL_IMPULSE,
    HIST_PEAK_FORCE,
    HIST_RATE,
    HIST_SLIP,
    HIST_TANGENTIAL_IMPULSE,
    HIST_XI,
    KINEMATIC,
    PINNED,
    ContactTable,
    PolygonSet,
    check_materials,
)
from perga.geometry.disc_polygon import FASTMATH, bounding_radii, closest_feature, separation

N_CHUNKS = 64
"""Granules are split into this many chunks for the parallel loop (fixed: deterministic sums)."""


class Discs(NamedTuple):
    """The granule arrays a polygon contact reads: positions x (n, 2), m; velocities v (n, 2),
    m/s; angular velocities w (n,), rad/s; radii r (n,), m; masses m (n,), kg; materials mat
    (n,) int32 (row of the ``ContactTable``)."""

    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    r: np.ndarray
    m: np.ndarray
    mat: np.ndarray


class Pose(NamedTuple):
    """A pose of the polygons to move from (``pose``): vertices (n_vertices, 2), centres of mass
    com (n_poly, 2) and pivots (n_poly, 2), m."""

    vertices: np.ndarray
    com: np.ndarray
    pivot: np.ndarray


class Candidates(NamedTuple):
    """Candidate (granule, polygon) pairs in CSR form (``candidates``): granule i's entries are
    start[i]:start[i + 1] (int64), polygon[e] (int64) the polygon of entry e; loads (n_entries, 4)
    per entry: force on the polygon x, y (N), torque about its centre of mass (N·m), energy
    dissipated (J), of the current step (written by ``kernel._integrate``, summed by
    ``add_loads``)."""

    start: np.ndarray
    polygon: np.ndarray
    loads: np.ndarray


@nb.njit(cache=True, fastmath=FASTMATH)
def pose(origin, poly, time, since):
    """Pose the polygons ``poly`` (``PolygonArrays``) at ``time`` s (from the call's start) by
    rigid motion at their velocities from the pose ``origin`` (``Pose``) they had at
    ``since[k]`` s: with t = time − since[k], c(t) = c0 + v_c t, vertices and pivot turned by
    ω t about c0 and moved by v_c t. Writes poly's vertices, com and pivot."""
    verts0, com0, pivot0 = origin.vertices, origin.com, origin.pivot
    verts, start, com, vel = poly.vertices, poly.start, poly.com, poly.velocity
    omega, pivot = poly.omega, poly.pivot
    for k in range(com.shape[0]):
        t = time - since[k]
        c = math.cos(omega[k] * t)
        s = math.sin(omega[k] * t)
        cx = com0[k, 0] + vel[k, 0] * t
        cy = com0[k, 1] + vel[k, 1] * t
        for q in range(start[k], start[k + 1]):
            rx = verts0[q, 0] - com0[k, 0]
            ry = verts0[q, 1] - com0[k, 1]
            verts[q, 0] = cx + c * rx - s * ry
            verts[q, 1] = cy + s * rx + c * ry
        rx = pivot0[k, 0] - com0[k, 0]
        ry = pivot0[k, 1] - com0[k, 1]
        pivot[k, 0] = cx + c * rx - s * ry
        pivot[k, 1] = cy + s * rx + c * ry
        com[k, 0] = cx
        com[k, 1] = cy


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def _end_contact(i, k, mat, pmat, table, hist):
    """Reset a pair that is not touching; returns the energy of a dropped tangential spring, J."""
    if hist[i, k, HIST_ACTIVE] == 0.0:
        return 0.0
    xi = hist[i, k, HIST_XI]
    a = mat[i]
    b = pmat[k]
    released = spring_energy(table.k_t[a, b], 0.0 if table.law[a, b] == LINEAR else 1.0, xi)
    hist[i, k, HIST_XI] = 0.0
    hist[i, k, HIST_ACTIVE] = 0.0
    hist[i, k, HIST_RATE] = 0.0
    hist[i, k, HIST_SLIP] = 0.0
    hist[i, k, HIST_DISSIPATED] += released
    return released


@nb.njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def _acting_contact(
    i, k, m, mat, poly, table, hist, dt, ri, delta, delta_dot, rate, slip, vt, px, py, nx, ny,
    arm, active,
):  # fmt: skip
    """The force of a contact of granule i with polygon k that acts in the step
    (``polygon_contact``, which computes the arguments: the granule's radius ri and overlap
    delta, m; approach rate delta_dot and slip of the half step and their extrapolations rate
    and vt, m/s; contact point (px, py), m; normal (nx, ny); lever arm, m; active: the contact
    acted in the last step); updates hist[i, k]. Returns (fx, fy, tq, tq_poly, dissipated) as
    ``polygon_contact``. Not inlined: the test before it runs for every candidate pair and
    compiles to a tighter loop without this body (docs/dev/performance.md). Compiled with the error
    model of the parallel passes that call it; called, its force cannot be fused into the
    caller's sums, so its floats may differ in the last bit from an inlined law's."""
    com, kind = poly.com, poly.kind
    pmass, pinertia, pivot, pmat = poly.mass, poly.inertia, poly.pivot, poly.mat
    law, k_n, k_t, damping = table.law, table.k_n, table.k_t, table.damping
    friction, clamp, damping_t = table.friction, table.clamp, table.damping_t
    rcx = px - com[k, 0]
    rcy = py - com[k, 1]
    tx = -ny
    ty = nx
    if not active:  # a new contact: the previous one's totals are forgotten
        hist[i, k, HIST_NORMAL_IMPULSE] = 0.0
        hist[i, k, HIST_TANGENTIAL_IMPULSE] = 0.0
        hist[i, k, HIST_DISSIPATED] = 0.0
        hist[i, k, HIST_PEAK_FORCE] = 0.0
    kd = kind[k]
    if kd == FREE:
        cr = rcx * ny - rcy * nx
        inv_mp = 1.0 / pmass[k] + cr * cr / pinertia[k]
    elif kd == PINNED:
        cr = (px - pivot[k, 0]) * ny - (py - pivot[k, 1]) * nx
        inv_mp = cr * cr / pinertia[k]
    else:
        inv_mp = 0.0
    m_eff = 1.0 / (1.0 / m[i] + inv_mp)
    a = mat[i]
    b = pmat[k]
    if law[a, b] == LINEAR:
        kn = k_n[a, b]
        damp = 2.0 * damping[a, b]
        hertz = 0.0
        kt = k_t[a, b]
    else:
        kn = k_n[a, b] * math.sqrt(ri)
        damp = damping[a, b]
        hertz = 1.0
        kt = k_t[a, b] * math.sqrt(ri * max(delta, 0.0))
    fn, ft, xi_t, dissipated = contact_force(
        kn, damp, hertz, clamp[a, b], kt, damping_t[a, b], friction[a, b],
        delta, rate, vt, m_eff, hist[i, k, HIST_XI], dt,
    )  # fmt: skip
    hist[i, k, HIST_XI] = xi_t
    hist[i, k, HIST_ACTIVE] = 1.0
    hist[i, k, HIST_RATE] = delta_dot
    hist[i, k, HIST_SLIP] = slip
    hist[i, k, HIST_NORMAL_IMPULSE] += fn * dt
    hist[i, k, HIST_TANGENTIAL_IMPULSE] += ft * dt
    hist[i, k, HIST_DISSIPATED] += dissipated
    hist[i, k, HIST_PEAK_FORCE] = max(hist[i, k, HIST_PEAK_FORCE], fn)
    fx = fn * nx + ft * tx
    fy = fn * ny + ft * ty
    return fx, fy, -arm * ft, -(rcx * fy - rcy * fx), dissipated


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def polygon_contact(i, k, x, v, w, r, m, mat, poly, table, rho, dt, hist):
    """Contact of granule i with polygon k over one step; updates hist[i, k] (module doc).

    x, v, w, r, m, mat: the granule arrays (``Discs``); poly: ``PolygonArrays`` at the step's
    pose; table: ``TableArrays``; rho: ``bounding_radii`` of the polygons, m; dt: step, s. Returns
    (acting, fx, fy, tq, tq_poly, dissipated): whether the contact acts in the step (its
    HIST_ACTIVE flag after it); force on the granule, N (−it on the polygon); torque on the
    granule, N·m; torque on the polygon about its centre of mass, N·m; energy dissipated over
    the step, J.
    """
    com, pvel, pomega, pmat = poly.com, poly.velocity, poly.omega, poly.mat
    xi = x[i, 0]
    yi = x[i, 1]
    ri = r[i]
    cx = xi - com[k, 0]
    cy = yi - com[k, 1]
    dist2 = cx * cx + cy * cy
    reach = rho[k] + ri
    # Skip when even the fastest approach cannot make it touch within the step:
    # |rate| <= 1.5 |v_i - v_p| + 0.5 |last rate|, |v_p| <= |v_c| + |w| (dist + r_i).
    if dist2 > reach * reach:
        dist = math.sqrt(dist2)
        bound = 1.5 * (
            math.sqrt(v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
            + math.sqrt(pvel[k, 0] * pvel[k, 0] + pvel[k, 1] * pvel[k, 1])
            + abs(pomega[k]) * (dist + ri)
        ) + 0.5 * abs(hist[i, k, HIST_RATE])
        if dist - reach >= 0.5 * dt * bound:
            return False, 0.0, 0.0, 0.0, 0.0, _end_contact(i, k, mat, pmat, table, hist)
    d, nx, ny = closest_feature(xi, yi, poly.vertices, poly.start, poly.solid, poly.corner, k)
    delta = ri - d
    # Contact point: middle of the overlap (the surface point before first touch); t = (-ny, nx).
    arm = ri - 0.5 * max(delta, 0.0)
    px = xi - arm * nx
    py = yi - arm * ny
    tx = -ny
    ty = nx
    # Relative velocity of the disc's material point to the polygon's at p.
    rcx = px - com[k, 0]
    rcy = py - com[k, 1]
    vrx = v[i, 0] + w[i] * arm * ny - (pvel[k, 0] - pomega[k] * rcy)
    vry = v[i, 1] - w[i] * arm * nx - (pvel[k, 1] + pomega[k] * rcx)
    delta_dot = -(vrx * nx + vry * ny)
    slip = vrx * tx + vry * ty
    # Rates of the last half step; extrapolated to the force time from the previous ones (none
    # at first touch: no contact force yet).
    active = hist[i, k, HIST_ACTIVE] != 0.0
    rate = 1.5 * delta_dot - 0.5 * hist[i, k, HIST_RATE] if active else delta_dot
    vt = 1.5 * slip - 0.5 * hist[i, k, HIST_SLIP] if active else slip
    if not touching(delta, rate, dt):
        return False, 0.0, 0.0, 0.0, 0.0, _end_contact(i, k, mat, pmat, table, hist)
    fx, fy, tq, tq_poly, dissipated = _acting_contact(
        i, k, m, mat, poly, table, hist, dt, ri, delta, delta_dot, rate, slip, vt, px, py, nx,
        ny, arm, active,
    )  # fmt: skip
    return True, fx, fy, tq, tq_poly, dissipated


@nb.njit(cache=True, parallel=True, fastmath=FASTMATH)
def _polygon_contacts(discs, poly, table, dt, hist, f, tq, loads):
    """Compiled ``polygon_contacts`` (arrays unchecked); returns the number of contacts."""
    x, v, w, r, m, mat = discs.x, discs.v, discs.w, discs.r, discs.m, discs.mat
    com = poly.com
    force, torque, moment = loads.force, loads.torque, loads.moment
    n = x.shape[0]
    n_poly = com.shape[0]
    rho = bounding_radii(poly.vertices, poly.start, com)
    n_chunks = min(N_CHUNKS, max(n, 1))
    part = np.zeros((n_chunks, n_poly, 3))
    counts = np.zeros(n_chunks, dtype=np.int64)
    for c in nb.prange(n_chunks):
        for i in range(c * n // n_chunks, (c + 1) * n // n_chunks):
            for k in range(n_poly):
                hit, fx, fy, ti, tk, _ = polygon_contact(
                    i, k, x, v, w, r, m, mat, poly, table, rho, dt, hist
                )
                if hit:
                    counts[c] += 1
                    f[i, 0] += fx
                    f[i, 1] += fy
                    tq[i] += ti
                    part[c, k, 0] -= fx
                    part[c, k, 1] -= fy
                    part[c, k, 2] += tk
    for c in range(n_chunks):
        for k in range(n_poly):
            force[k, 0] += part[c, k, 0]
            force[k, 1] += part[c, k, 1]
            torque[k] += part[c, k, 2]
            moment[k] += part[c, k, 2] + com[k, 0] * part[c, k, 1] - com[k, 1] * part[c, k, 0]
    return counts.sum()


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def _candidate(i, k, x_ref, r, poly, rho, hist, reach):
    """Whether pair (i, k) goes in the candidate list: in contact, or (1 − ½ dt|ω|)(d − r_i) <
    its reach (``candidates``), d the separation from the polygon's edge lines (a lower bound of
    the distance, so that a piece whose features do not count here now is still listed);
    reach[k] = that reach / (1 − ½ dt|ω_k|), m (inf where 1 − ½ dt|ω_k| ≤ 0: every pair in)."""
    px = x_ref[i, 0]
    py = x_ref[i, 1]
    limit = r[i] + reach[k]
    dx = px - poly.com[k, 0]
    dy = py - poly.com[k, 1]
    if dx * dx + dy * dy >= (rho[k] + limit) ** 2:  # outside the bounding circle: cheap reject
        return hist[i, k, HIST_ACTIVE] != 0.0
    if hist[i, k, HIST_ACTIVE] != 0.0:
        return True
    return separation(px, py, poly.vertices, poly.start[k], poly.start[k + 1]) < limit


CANDIDATE_MARGIN = 0.5
"""A candidate list is built with its reach lengthened by this fraction of the neighbour
list's skin, so that the calls after keep it while the polygons' motion has not used up that
margin (``candidates_hold``): a skin of its own, as the neighbour list's."""


@nb.njit(cache=True)
def candidate_reach(poly, rho, span, skin, dt, reach):
    """Into reach (n_poly,): the reach, m, beyond which a granule cannot touch polygon k within
    ``span`` s of a call (``candidates``): (½ skin + S (span + ½ dt))/(1 − ½ dt|ω|), S = |v_c| +
    |ω| ρ the fastest point of the polygon, ∞ where 1 − ½ dt|ω| ≤ 0. poly: ``PolygonArrays``;
    rho: ``bounding_radii``, m."""
    velocity, omega = poly.velocity, poly.omega
    for k in range(omega.shape[0]):
        top = math.sqrt(velocity[k, 0] ** 2 + velocity[k, 1] ** 2) + abs(omega[k]) * rho[k]
        slack = 1.0 - 0.5 * dt * abs(omega[k])
        reach[k] = (0.5 * skin + top * (span + 0.5 * dt)) / slack if slack > 0.0 else math.inf


@nb.njit(cache=True)
def candidates_hold(vertices, start, built, reach_built, reach):
    """Whether a candidate list built with reach ``reach_built`` (n_poly,) m, its polygons'
    vertices then at ``built``, still holds every pair that can touch within the reach
    ``reach`` (``candidate_reach``) now that they are at ``vertices`` (start: each polygon's
    vertex rows). The displacement of a convex polygon's points under the rigid motion since is
    affine in the point, so its largest length, ``moved``, is at a vertex; a granule's distance
    to the polygon has fallen by at most ``moved``, and a pair left out stays out of reach while
    reach_built − moved ≥ reach."""
    for k in range(start.shape[0] - 1):
        moved = 0.0
        for q in range(start[k], start[k + 1]):
            dx = vertices[q, 0] - built[q, 0]
            dy = vertices[q, 1] - built[q, 1]
            moved = max(moved, math.sqrt(dx * dx + dy * dy))
        if not reach[k] + moved <= reach_built[k]:
            return False
    return True


@nb.njit(cache=True, parallel=True)
def candidates(x_ref, r, poly, rho, hist, reach):
    """(granule, polygon) pairs the fused step evaluates, as a CSR list (start (n + 1,) int64,
    polygon of each entry), sorted by granule then polygon: ``Candidates.start`` and
    ``Candidates.polygon``.

    poly: the polygons posed now (``PolygonArrays``); x_ref: granule positions at the
    last neighbour-list build; reach (n_poly,), m: ``candidate_reach`` of the span the list
    must serve. The kernel rebuilds the neighbour list when 2|x − x_ref| + dt|v| would exceed
    the skin, so at every step |x − x_ref| + ½ dt |v| ≤ ½ skin. No point of polygon k moves
    faster than S = |v_c| + |ω| ρ, so within the span the gap g = d − r_i between a granule and
    it falls by at most S·span plus the granule's displacement; a pair not in contact touches
    (``laws.touching``, approach rate ≤ |v_i| + |v_c| + |ω|(ρ + g)) only if (1 − ½ dt|ω|) g <
    ½ dt (|v_i| + |v_c| + |ω| ρ). So with g measured from x_ref to the polygon now, pairs with
    (1 − ½ dt|ω|) g ≥ ½ skin + S·span + ½ dt (|v_c| + |ω| ρ), i.e. g ≥ reach[k], are left
    out. Pairs in contact (``HIST_ACTIVE``) are always in, so that their end is evaluated. One
    pass over the pairs: row i of a scratch (n, n_poly) array takes granule i's entries, then
    the rows are gathered.
    """
    n = x_ref.shape[0]
    n_poly = reach.shape[0]
    found = np.empty((n, n_poly), np.int32)
    count = np.empty(n, np.int64)
    for i in nb.prange(n):
        q = 0
        for k in range(n_poly):
            if _candidate(i, k, x_ref, r, poly, rho, hist, reach):
                found[i, q] = k
                q += 1
        count[i] = q
    start = np.zeros(n + 1, np.int64)
    for i in range(n):
        start[i + 1] = start[i] + count[i]
    cpoly = np.empty(start[n], np.int64)
    for i in range(n):  # not a slice copy: numba would make each a parallel region
        for q in range(count[i]):
            cpoly[start[i] + q] = found[i, q]
    return start, cpoly  # not a Candidates with its loads: slower (docs/dev/performance.md)


@nb.njit(cache=True)
def add_loads(cand, com, loads, step):
    """Add one step's polygon loads ``cand.loads`` (``Candidates``) to ``loads``
    (``PolygonLoads``), write them per polygon into ``step`` (n_poly, 3: force x, y, N; torque
    about the centre of mass, N·m) and return the energy the step's contacts dissipated, J.

    Summed in entry order (independent of the thread count); moment = torque + com × force about
    the origin at this step's com (n_poly, 2), m.
    """
    cpoly, ploads = cand.polygon, cand.loads
    force, torque, moment = loads.force, loads.torque, loads.moment
    n_poly = com.shape[0]
    step[:, :] = 0.0
    dissipated = 0.0
    for e in range(cpoly.shape[0]):
        k = cpoly[e]
        step[k, 0] += ploads[e, 0]
        step[k, 1] += ploads[e, 1]
        step[k, 2] += ploads[e, 2]
        dissipated += ploads[e, 3]
    for k in range(n_poly):
        force[k, 0] += step[k, 0]
        force[k, 1] += step[k, 1]
        torque[k] += step[k, 2]
        moment[k] += step[k, 2] + com[k, 0] * step[k, 1] - com[k, 1] * step[k, 0]
    return dissipated


@nb.njit(cache=True)
def kick_bodies(poly, step, dt, origin, since, time, total, kick):
    """Kick the movable bodies of the polygons ``poly`` (``PolygonArrays``) by one step's loads
    ``step`` (``add_loads``') over dt s, and move the pose origin (``Pose`` ``origin``,
    ``since``) of each kicked polygon to its pose now, ``time`` s; returns whether any was
    kicked. A FREE body takes Δv = F dt/M, Δω = τ_c dt/I_c; a PINNED one Δω = τ_A dt/I_A about
    its pivot A (τ_A = τ_c + (c − A) × F) and its centre's velocity Δω × (c − A); a KINEMATIC
    one (or infinite inertia) none. The body's loads are the sums over its polygons
    (``PolygonSet.body``); ``total`` and ``kick`` (n_poly, 3) are work space."""
    body, kind, com, pivot = poly.body, poly.kind, poly.com, poly.pivot
    n_poly = com.shape[0]
    total[:, :] = 0.0
    kick[:, :] = 0.0
    for k in range(n_poly):
        b = body[k]
        total[b, 0] += step[k, 0]
        total[b, 1] += step[k, 1]
        total[b, 2] += step[k, 2]
    any_kick = False
    for b in range(n_poly):
        if body[b] != b or kind[b] == KINEMATIC:
            continue
        fx, fy, tq = total[b, 0], total[b, 1], total[b, 2]
        if fx == 0.0 and fy == 0.0 and tq == 0.0:
            continue
        if kind[b] == FREE:
            kick[b, 0] = fx * dt / poly.mass[b]
            kick[b, 1] = fy * dt / poly.mass[b]
            kick[b, 2] = tq * dt / poly.inertia[b]
        else:
            rx, ry = com[b, 0] - pivot[b, 0], com[b, 1] - pivot[b, 1]
            dw = (tq + rx * fy - ry * fx) * dt / poly.inertia[b]
            kick[b, 0], kick[b, 1], kick[b, 2] = -dw * ry, dw * rx, dw
        any_kick = True
    if not any_kick:
        return False
    for k in range(n_poly):
        b = body[k]
        if kick[b, 0] == 0.0 and kick[b, 1] == 0.0 and kick[b, 2] == 0.0:
            continue
        for q in range(poly.start[k], poly.start[k + 1]):
            origin.vertices[q, 0] = poly.vertices[q, 0]
            origin.vertices[q, 1] = poly.vertices[q, 1]
        origin.com[k, 0], origin.com[k, 1] = com[k, 0], com[k, 1]
        origin.pivot[k, 0], origin.pivot[k, 1] = pivot[k, 0], pivot[k, 1]
        since[k] = time
        poly.velocity[k, 0] += kick[b, 0]
        poly.velocity[k, 1] += kick[b, 1]
        poly.omega[k] += kick[b, 2]
    return True


@nb.njit(cache=True)
def add_recoil(poly, start_velocity, start_omega, dt, recoil):
    """Add to ``recoil`` (n_poly, 3: m, m, rad) one step's drift of the polygons ``poly``
    (``PolygonArrays``) beyond their drift at the call's start velocities ``start_velocity``
    (n_poly, 2), m/s, and ``start_omega`` (n_poly,), rad/s, over dt s."""
    for k in range(recoil.shape[0]):
        recoil[k, 0] += (poly.velocity[k, 0] - start_velocity[k, 0]) * dt
        recoil[k, 1] += (poly.velocity[k, 1] - start_velocity[k, 1]) * dt
        recoil[k, 2] += (poly.omega[k] - start_omega[k]) * dt


@nb.njit(cache=True, parallel=True, fastmath=FASTMATH)
def _contact_energy(x, r, mat, poly, table, hist, normal, tangential):
    """Elastic energy in the granule-polygon contacts at the current poses, J (see
    ``contact_energy``)."""
    verts, start, com, pmat = poly.vertices, poly.start, poly.com, poly.mat
    law, k_n, k_t = table.law, table.k_n, table.k_t
    rho = bounding_radii(verts, start, com)
    n = x.shape[0]
    energy = np.zeros(n)
    for i in nb.prange(n):
        for k in range(com.shape[0]):
            xi = hist[i, k, HIST_XI]
            dist = math.sqrt((x[i, 0] - com[k, 0]) ** 2 + (x[i, 1] - com[k, 1]) ** 2)
            if dist >= rho[k] + r[i] and xi == 0.0:
                continue
            d, _, _ = closest_feature(x[i, 0], x[i, 1], verts, start, poly.solid, poly.corner, k)
            delta = max(r[i] - d, 0.0)
            a = mat[i]
            b = pmat[k]
            if law[a, b] == LINEAR:
                spring = 0.5 * k_n[a, b] * delta * delta
            else:
                spring = 0.4 * k_n[a, b] * math.sqrt(r[i]) * delta * delta * math.sqrt(delta)
            if normal:
                energy[i] += spring
            if tangential:
                energy[i] += spring_energy(k_t[a, b], 0.0 if law[a, b] == LINEAR else 1.0, xi)
    return energy.sum()


def _check(arrays: dict[str, tuple[np.ndarray, tuple[int, ...], type]]) -> None:
    for name, (arr, shape, dtype) in arrays.items():
        if arr.shape != shape or arr.dtype != dtype or not arr.flags.c_contiguous:
            raise ValueError(
                f"{name} must be C-contiguous {np.dtype(dtype).name} of shape {shape} "
                f"(got {arr.dtype.name} {arr.shape})"
            )


def polygon_contacts(
    x: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    r: np.ndarray,
    m: np.ndarray,
    mat: np.ndarray,
    polygons: PolygonSet,
    table: ContactTable,
    dt: float,
    history: np.ndarray,
    f: np.ndarray,
    tq: np.ndarray,
) -> int:
    """Accumulate granule-polygon contact forces once; return the number of contacts evaluated.

    A contact counts while ``touching`` (module doc): from up to half a step before first touch
    to the step after the force has returned to zero.

    Granules: x, v (n, 2), w, r, m (n,), mat (n,) int32 (row of ``table``). dt: time step, s
    (advances the tangential springs). history (n, n_poly, HIST_COLUMNS): contact history
    (module doc), updated in place (start from zeros). Adds to f (n, 2), tq (n,) and to
    ``polygons.force``, ``polygons.torque`` (about each centre of mass) and ``polygons.moment``
    (about the origin). Layouts are checked here; the compiled kernel takes the same arrays
    without checks.
    """
    n = x.shape[0]
    n_poly = polygons.n_poly
    _check(
        {
            "x": (x, (n, 2), np.float64),
            "v": (v, (n, 2), np.float64),
            "w": (w, (n,), np.float64),
            "r": (r, (n,), np.float64),
            "m": (m, (n,), np.float64),
            "mat": (mat, (n,), np.int32),
            "history": (history, (n, n_poly, HIST_COLUMNS), np.float64),
            "f": (f, (n, 2), np.float64),
            "tq": (tq, (n,), np.float64),
        }
    )
    check_materials(mat, polygons, table)
    if n == 0 or n_poly == 0:
        return 0
    discs = Discs(x, v, w, r, m, mat)
    count = _polygon_contacts(
        discs, polygons.arrays(), table.arrays(), float(dt), history, f, tq, polygons.loads()
    )
    return int(count)


def contact_energy(
    x: np.ndarray,
    r: np.ndarray,
    mat: np.ndarray,
    polygons: PolygonSet,
    table: ContactTable,
    history: np.ndarray,
    normal: bool = True,
    tangential: bool = True,
) -> float:
    """Elastic energy stored in the granule-polygon contacts at the polygons' current poses, J.

    Normal (if ``normal``): k_n δ²/2 (LINEAR), 2 k δ^{5/2}/5 with k = k_n √r_i (HERTZ), over
    every overlap δ > 0; tangential (if ``tangential``): k_t ξ²/2 with the k_t of the current
    overlap (k_t √(r_i δ⁺) for HERTZ), ξ from ``history``. Arrays as in ``polygon_contacts``.
    """
    if x.shape[0] == 0 or polygons.n_poly == 0:
        return 0.0
    return float(
        _contact_energy(x, r, mat, polygons.arrays(), table.arrays(), history, normal, tangential)
    )
