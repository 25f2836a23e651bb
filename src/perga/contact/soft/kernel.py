"""Compiled soft-granule kernel: pair and wall forces, symplectic Euler, k steps inside numba.

Arrays (SI, float64 unless said, C-contiguous): positions ``x`` (n, 2), velocities ``v`` (n, 2),
angular velocities ``w`` (n,), radii ``r`` (n,), masses ``m`` (n,), moments ``inertia`` (n,)
(m r²/2 for a disc), material ``mat`` (n,) int32, forces ``f`` (n, 2), torques ``tq`` (n,).
Contact laws and the parameter table: ``perga.contact.soft.laws``. Neighbour list:
``perga.contact.soft.neighbours`` (half list in CSR form, one tangential history float per entry).

Walls: ``walls`` (n_walls, 6) float64 rows ``[kind, a, b, c, d, mat]``:

* kind WALL_CHAMBER: round chamber, centre (a, b), inner radius c; the granule is inside;
* kind WALL_PLANE: half-plane through (a, b) with unit normal (c, d) pointing into the domain.

A wall is a body of infinite mass at rest: its contacts use m_eff = m_i (and I_i for rolling);
their tangential history is ``wall_hist`` (n, n_walls).

Integrator (symplectic Euler, velocity kicks): forces from (x, v, w) at step start, then
v += (f/m + g) dt, w += tq/I dt, x += v dt with the new v. Explicit Euler through forces gains
energy (design §8: e = 1.18 at t_c/10); this scheme is stable to about dt = t_c/5 and is run at
t_c/50 by default. Optional global drag (1/s, implicit: v ← v/(1 + drag·dt)) and a speed cap
v_cap (m/s) serve ``SoftGranules.relax`` only; normal runs have drag = 0, v_cap = inf.

Polygons (hammers, ``perga.contact.soft.polygon_forces``): ``poly`` = ``PolygonSet.arrays()``,
``table`` =
``ContactTable.arrays()``, ``loads`` = ``PolygonSet.loads()``, history ``phist`` (n, n_poly,
``HIST_COLUMNS``); empty arrays for none. During a call of n steps each polygon moves rigidly
from its pose at the call's first force evaluation with its (fixed) velocities: at step j
(0-based) it is where ``polygons.pose`` puts it j·dt later, the PINNED pivot moving with it.
After the call the set holds the pose n·dt later (the granules' time) and the loads are the
means over the call. Contacts are evaluated for a candidate list (``polygons.candidates``),
built at the call's first step and after every neighbour-list rebuild, so that granules far
from every polygon cost nothing per step.

Dissipation: every contact reports the energy its law dissipated over the step
(``contacts.contact_force``; rolling resistance |M ω_rel| dt; a tangential spring dropped at a
contact's end ½ k_t ξ²); ``dissipated`` (3,) accumulates [granule pairs, walls, polygons], J.

Threads: pair forces are split in ``n_chunks`` contiguous ranges of i (one per thread), each
accumulating into its own slice of ``acc`` (n_chunks, n, 3), summed per granule afterwards, so
each pair is computed once and no two threads write the same memory (no races, results
identical for a given n_chunks). Everything else is per granule; polygon loads and their
dissipation are summed per candidate entry in a fixed order afterwards, so they and the
granules' polygon forces do not depend on the number of threads.
"""

import math

import numpy as np
from numba import njit, prange

from perga.contact.soft.laws import contact_law, released, rolling_torque, touching
from perga.contact.soft.neighbours import build
from perga.contact.soft.polygon_forces import add_loads, candidates, polygon_contact, pose
from perga.geometry.disc_polygon import FASTMATH, bounding_radii

WALL_CHAMBER = 0
WALL_PLANE = 1
WALL_COLUMNS = 6

DISSIPATED_PAIRS, DISSIPATED_WALLS, DISSIPATED_POLYGONS = 0, 1, 2
"""Entries of the (3,) dissipated-energy totals of ``advance``."""


@njit(cache=True, inline="always", fastmath=FASTMATH)
def pair_force(i, j, k, x, v, w, a_prev, r, m, inertia, mat, params, hist, dt):
    """Force (fx, fy) on i (−it on j), torques on i and j, dissipated energy (J), for list entry
    k; updates hist[k]."""
    h = 0.5 * dt
    dx = x[i, 0] - x[j, 0]
    dy = x[i, 1] - x[j, 1]
    d2 = dx * dx + dy * dy
    rs = r[i] + r[j]
    if d2 > 0.0:
        d = math.sqrt(d2)
        nx = dx / d
        ny = dy / d
    else:
        d = 0.0
        nx = 1.0
        ny = 0.0
    vrx = v[i, 0] - v[j, 0] + h * (a_prev[i, 0] - a_prev[j, 0])
    vry = v[i, 1] - v[j, 1] + h * (a_prev[i, 1] - a_prev[j, 1])
    wi = w[i] + h * a_prev[i, 2]
    wj = w[j] + h * a_prev[j, 2]
    ddelta = -(vrx * nx + vry * ny)
    if not touching(rs - d, ddelta, dt):
        xi = hist[k]
        if xi == 0.0:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        hist[k] = 0.0
        return 0.0, 0.0, 0.0, 0.0, released(params, mat[i], mat[j], rs - d, xi)
    tx = -ny
    ty = nx
    # Lever arms to the middle of the overlap, or of the gap just before first touch: they sum
    # to d, so both discs load one common point and angular momentum is conserved.
    half = 0.5 * (rs - d)
    arm_i = r[i] - half
    arm_j = r[j] - half
    vt = vrx * tx + vry * ty - (arm_i * wi + arm_j * wj)
    m_eff = m[i] * m[j] / (m[i] + m[j])
    a = mat[i]
    b = mat[j]
    fn, ft, hist[k], lost = contact_law(params, a, b, rs - d, ddelta, vt, m_eff, hist[k], dt)
    mr = rolling_torque(
        params,
        a,
        b,
        fn,
        wi - wj,
        r[i] * r[j] / rs,
        inertia[i] * inertia[j] / (inertia[i] + inertia[j]),
        dt,
    )
    if mr != 0.0:
        lost += abs(mr * (wi - wj)) * dt
    ti = -arm_i * ft
    tj = -arm_j * ft
    return fn * nx + ft * tx, fn * ny + ft * ty, ti + mr, tj - mr, lost


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def pair_forces(x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, acc, lost):
    """Pair forces into acc (n_chunks, n, 3) = (fx, fy, torque), one slice per chunk of i; the
    energy the chunk's contacts dissipated into lost[c], J."""
    n = x.shape[0]
    n_chunks = acc.shape[0]
    for c in prange(n_chunks):
        lo = c * n // n_chunks
        hi = (c + 1) * n // n_chunks
        a = acc[c]
        for i in range(n):
            a[i, 0] = 0.0
            a[i, 1] = 0.0
            a[i, 2] = 0.0
        dissipated = 0.0
        for i in range(lo, hi):
            for k in range(start[i], start[i + 1]):
                j = nbr[k]
                fx, fy, ti, tj, de = pair_force(
                    i, j, k, x, v, w, a_prev, r, m, inertia, mat, params, hist, dt
                )
                a[i, 0] += fx
                a[i, 1] += fy
                a[i, 2] += ti
                a[j, 0] -= fx
                a[j, 1] -= fy
                a[j, 2] += tj
                dissipated += de
        lost[c] = dissipated


@njit(cache=True, inline="always", fastmath=FASTMATH)
def wall_force(i, x, v, w, a_prev, r, m, inertia, mat, params, walls, wall_hist, dt):
    """Sum of the wall forces and torque on granule i and the energy they dissipated:
    (fx, fy, tq, J); updates wall_hist[i]."""
    h = 0.5 * dt
    ux = v[i, 0] + h * a_prev[i, 0]
    uy = v[i, 1] + h * a_prev[i, 1]
    wi = w[i] + h * a_prev[i, 2]
    fx = 0.0
    fy = 0.0
    tq = 0.0
    lost = 0.0
    for s in range(walls.shape[0]):
        if walls[s, 0] == WALL_CHAMBER:
            dx = x[i, 0] - walls[s, 1]
            dy = x[i, 1] - walls[s, 2]
            d = math.sqrt(dx * dx + dy * dy)
            delta = r[i] + d - walls[s, 3]
            if d > 0.0:
                nx = -dx / d
                ny = -dy / d
            else:
                nx = 1.0
                ny = 0.0
        else:
            nx = walls[s, 3]
            ny = walls[s, 4]
            delta = r[i] - ((x[i, 0] - walls[s, 1]) * nx + (x[i, 1] - walls[s, 2]) * ny)
        ddelta = -(ux * nx + uy * ny)
        if not touching(delta, ddelta, dt):
            xi = wall_hist[i, s]
            if xi != 0.0:
                lost += released(params, mat[i], int(walls[s, 5]), delta, xi)
                wall_hist[i, s] = 0.0
            continue
        b = int(walls[s, 5])
        tx = -ny
        ty = nx
        vt = ux * tx + uy * ty - r[i] * wi
        fn, ft, wall_hist[i, s], de = contact_law(
            params, mat[i], b, delta, ddelta, vt, m[i], wall_hist[i, s], dt
        )
        mr = rolling_torque(params, mat[i], b, fn, wi, r[i], inertia[i], dt)
        fx += fn * nx + ft * tx
        fy += fn * ny + ft * ty
        tq += -r[i] * ft + mr
        lost += de + abs(mr * wi) * dt if mr != 0.0 else de
    return fx, fy, tq, lost


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _kick_drift_one(i, x, v, w, m, inertia, fx, fy, t, gravity, dt, damp, v_cap, a_prev):
    """Symplectic Euler for granule i from its force (fx, fy) and torque t; records a_prev[i]."""
    ax = fx / m[i] + gravity[0]
    ay = fy / m[i] + gravity[1]
    alpha = t / inertia[i]
    vx = (v[i, 0] + dt * ax) * damp
    vy = (v[i, 1] + dt * ay) * damp
    s2 = vx * vx + vy * vy
    if s2 > v_cap * v_cap:
        scale = v_cap / math.sqrt(s2)
        vx *= scale
        vy *= scale
    v[i, 0] = vx
    v[i, 1] = vy
    w[i] = (w[i] + dt * alpha) * damp
    a_prev[i, 0] = ax
    a_prev[i, 1] = ay
    a_prev[i, 2] = alpha
    x[i, 0] += dt * vx
    x[i, 1] += dt * vy


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def _integrate(
    x,
    v,
    w,
    a_prev,
    r,
    m,
    inertia,
    mat,
    params,
    walls,
    wall_hist,
    poly,
    table,
    rho,
    phist,
    cstart,
    cpoly,
    ploads,
    gravity,
    dt,
    drag,
    v_cap,
    acc,
    f,
    tq,
    x_ref,
    chunk,
):
    """Fused per-granule pass: wall and polygon forces, sum of chunks, kick-drift, displacement².

    Writes the step's total contact force and torque to f and tq; chunk[c] = (max displacement²
    since the list build, max speed², wall dissipation, J) of chunk c (per-chunk values instead
    of shared reduction variables). Polygon contacts: the candidate pairs (cstart, cpoly) of
    each granule; entry e's load on its polygon and dissipation go to ploads[e] (see
    ``polygons.add_loads``).
    """
    n = x.shape[0]
    n_chunks = acc.shape[0]
    damp = 1.0 / (1.0 + drag * dt)
    for c in prange(n_chunks):
        lo = c * n // n_chunks
        hi = (c + 1) * n // n_chunks
        dmax = 0.0
        smax = 0.0
        lost = 0.0
        for i in range(lo, hi):
            fx, fy, t, de = wall_force(
                i, x, v, w, a_prev, r, m, inertia, mat, params, walls, wall_hist, dt
            )
            lost += de
            for q in range(n_chunks):
                fx += acc[q, i, 0]
                fy += acc[q, i, 1]
                t += acc[q, i, 2]
            for e in range(cstart[i], cstart[i + 1]):
                _, px, py, ti, tk, de = polygon_contact(
                    i, cpoly[e], x, v, w, r, m, mat, poly, table, rho, dt, phist
                )
                fx += px
                fy += py
                t += ti
                ploads[e, 0] = -px
                ploads[e, 1] = -py
                ploads[e, 2] = tk
                ploads[e, 3] = de
            f[i, 0] = fx
            f[i, 1] = fy
            tq[i] = t
            _kick_drift_one(i, x, v, w, m, inertia, fx, fy, t, gravity, dt, damp, v_cap, a_prev)
            ex = x[i, 0] - x_ref[i, 0]
            ey = x[i, 1] - x_ref[i, 1]
            dmax = max(dmax, ex * ex + ey * ey)
            smax = max(smax, v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
        chunk[c, 0] = dmax
        chunk[c, 1] = smax
        chunk[c, 2] = lost


@njit(cache=True)
def _stale(x, v, x_ref, skin, dt):
    """Whether the list built at x_ref must be rebuilt: 2·max|x − x_ref| + dt·max|v| > skin."""
    dmax = 0.0
    smax = 0.0
    for i in range(x.shape[0]):
        ex = x[i, 0] - x_ref[i, 0]
        ey = x[i, 1] - x_ref[i, 1]
        dmax = max(dmax, ex * ex + ey * ey)
        smax = max(smax, v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
    return 2.0 * math.sqrt(dmax) + dt * math.sqrt(smax) > skin


@njit(cache=True)
def advance(
    n_steps,
    x,
    v,
    w,
    a_prev,
    r,
    m,
    inertia,
    mat,
    params,
    walls,
    wall_hist,
    poly,
    table,
    phist,
    loads,
    gravity,
    dt,
    skin,
    start,
    nbr,
    hist,
    x_ref,
    acc,
    f,
    tq,
    drag,
    v_cap,
    rebuild,
    dissipated,
    pairs,
):
    """Advance n_steps symplectic Euler steps; returns (start, nbr, hist, n_rebuilds).

    pairs: False skips granule-granule contacts (no pair list built, no pair loop; acc must
    then hold zeros, as ``new_accumulator`` makes it).

    Rebuilds the neighbour list (carrying the tangential history over) before a step when
    2·(largest displacement since the last build) + dt·(largest speed) exceeds the skin (the
    dt·v term keeps listed every pair that ``touching`` may need half a step before first
    contact), when start is not a list for these n granules, or when rebuild is True; x_ref
    (n, 2) holds the positions at the last build and is updated in place. The polygon candidate
    list (``polygons.candidates``) is built at the first step and after every rebuild. On
    return f and tq hold the contact forces and torques of the last step, a_prev its
    accelerations, the polygons their pose n_steps·dt after the call's start and loads the mean
    force, torque and moment over the call; the dissipated energy (3,) has been added to.
    """
    n = x.shape[0]
    n_chunks = acc.shape[0]
    force, torque, moment = loads
    n_poly = force.shape[0]
    verts0 = poly[0].copy()
    com0 = poly[2].copy()
    pivot0 = poly[8].copy()
    rho = bounding_radii(poly[0], poly[1], poly[2])
    force[:, :] = 0.0
    torque[:] = 0.0
    moment[:] = 0.0
    chunk = np.zeros((n_chunks, 3))
    lost = np.zeros(n_chunks)
    cstart = np.zeros(n + 1, np.int64)
    cpoly = np.zeros(0, np.int64)
    ploads = np.zeros((0, 4))
    n_rebuilds = 0
    need = rebuild or (pairs and start.shape[0] != n + 1) or _stale(x, v, x_ref, skin, dt)
    fresh = False
    for step in range(n_steps):
        if need:
            if pairs:
                start, nbr, hist = build(x, r, skin, start, nbr, hist)
            x_ref[:, :] = x
            n_rebuilds += 1
            fresh = False
        if n_poly > 0:
            if step > 0:
                pose(verts0, com0, pivot0, poly, step * dt)
            if not fresh:
                span = (n_steps - 1 - step) * dt
                cstart, cpoly = candidates(x_ref, r, poly, rho, phist, span, skin, dt)
                ploads = np.zeros((cpoly.shape[0], 4))
                fresh = True
        if pairs:
            pair_forces(
                x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, acc, lost
            )
        _integrate(
            x,
            v,
            w,
            a_prev,
            r,
            m,
            inertia,
            mat,
            params,
            walls,
            wall_hist,
            poly,
            table,
            rho,
            phist,
            cstart,
            cpoly,
            ploads,
            gravity,
            dt,
            drag,
            v_cap,
            acc,
            f,
            tq,
            x_ref,
            chunk,
        )
        if n_poly > 0:
            dissipated[DISSIPATED_POLYGONS] += add_loads(
                cpoly, ploads, poly[2], force, torque, moment
            )
        dmax = 0.0
        smax = 0.0
        for c in range(n_chunks):
            dmax = max(dmax, chunk[c, 0])
            smax = max(smax, chunk[c, 1])
            dissipated[DISSIPATED_PAIRS] += lost[c]
            dissipated[DISSIPATED_WALLS] += chunk[c, 2]
        need = 2.0 * math.sqrt(dmax) + dt * math.sqrt(smax) > skin
    if n_poly > 0 and n_steps > 0:
        pose(verts0, com0, pivot0, poly, n_steps * dt)
        force /= n_steps
        torque /= n_steps
        moment /= n_steps
    return start, nbr, hist, n_rebuilds


def new_accumulator(n_chunks: int, n: int) -> np.ndarray:
    """Per-chunk force accumulator (n_chunks, n, 3) for ``pair_forces`` and ``advance``."""
    return np.zeros((max(int(n_chunks), 1), n, 3))
