"""Compiled soft-granule kernel: pair and wall forces, symplectic Euler, k steps inside numba.

Arrays (SI, float64 unless said, C-contiguous): positions ``x`` (n, 2), velocities ``v`` (n, 2),
angular velocities ``w`` (n,), radii ``r`` (n,), masses ``m`` (n,), moments ``inertia`` (n,)
(m r²/2 for a disc), material ``mat`` (n,) int32, forces ``f`` (n, 2), torques ``tq`` (n,).
Contact laws and the parameter table: ``perga.soft.contacts``. Neighbour list:
``perga.soft.neighbours`` (half list in CSR form, one tangential history float per entry).

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

Threads: pair forces are split in ``n_chunks`` contiguous ranges of i (one per thread), each
accumulating into its own slice of ``acc`` (n_chunks, n, 3), summed per granule afterwards, so
each pair is computed once and no two threads write the same memory (no races, results
identical for a given n_chunks). Everything else is per granule.
"""

import math

import numpy as np
from numba import njit, prange

from perga.soft.contacts import FASTMATH, contact_law, rolling_torque, touching
from perga.soft.neighbours import build

WALL_CHAMBER = 0
WALL_PLANE = 1
WALL_COLUMNS = 6


@njit(cache=True, inline="always", fastmath=FASTMATH)
def pair_force(i, j, k, x, v, w, a_prev, r, m, inertia, mat, params, hist, dt):
    """Force (fx, fy) on i (−it on j), torques on i and j, for list entry k; updates hist[k]."""
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
        hist[k] = 0.0
        return 0.0, 0.0, 0.0, 0.0
    tx = -ny
    ty = nx
    vt = vrx * tx + vry * ty - (r[i] * wi + r[j] * wj)
    m_eff = m[i] * m[j] / (m[i] + m[j])
    a = mat[i]
    b = mat[j]
    fn, ft, hist[k] = contact_law(params, a, b, rs - d, ddelta, vt, m_eff, hist[k], dt)
    ti = -r[i] * ft
    tj = -r[j] * ft
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
    return fn * nx + ft * tx, fn * ny + ft * ty, ti + mr, tj - mr


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def pair_forces(x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, acc):
    """Pair forces into acc (n_chunks, n, 3) = (fx, fy, torque), one slice per chunk of i."""
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
        for i in range(lo, hi):
            for k in range(start[i], start[i + 1]):
                j = nbr[k]
                fx, fy, ti, tj = pair_force(
                    i, j, k, x, v, w, a_prev, r, m, inertia, mat, params, hist, dt
                )
                a[i, 0] += fx
                a[i, 1] += fy
                a[i, 2] += ti
                a[j, 0] -= fx
                a[j, 1] -= fy
                a[j, 2] += tj


@njit(cache=True, inline="always", fastmath=FASTMATH)
def wall_force(i, x, v, w, a_prev, r, m, inertia, mat, params, walls, wall_hist, dt):
    """Sum of the wall forces and torque on granule i: (fx, fy, tq); updates wall_hist[i]."""
    h = 0.5 * dt
    ux = v[i, 0] + h * a_prev[i, 0]
    uy = v[i, 1] + h * a_prev[i, 1]
    wi = w[i] + h * a_prev[i, 2]
    fx = 0.0
    fy = 0.0
    tq = 0.0
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
            wall_hist[i, s] = 0.0
            continue
        tx = -ny
        ty = nx
        vt = ux * tx + uy * ty - r[i] * wi
        b = int(walls[s, 5])
        fn, ft, wall_hist[i, s] = contact_law(
            params, mat[i], b, delta, ddelta, vt, m[i], wall_hist[i, s], dt
        )
        fx += fn * nx + ft * tx
        fy += fn * ny + ft * ty
        tq += -r[i] * ft + rolling_torque(params, mat[i], b, fn, wi, r[i], inertia[i], dt)
    return fx, fy, tq


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def compute_forces(
    x,
    v,
    w,
    a_prev,
    r,
    m,
    inertia,
    mat,
    params,
    start,
    nbr,
    hist,
    walls,
    wall_hist,
    dt,
    acc,
    f,
    tq,
):
    """Add pair and wall forces to f (n, 2) and torques to tq (n,) (modular path, no stepping)."""
    pair_forces(x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, acc)
    n = x.shape[0]
    for i in prange(n):
        fx, fy, t = wall_force(i, x, v, w, a_prev, r, m, inertia, mat, params, walls, wall_hist, dt)
        for c in range(acc.shape[0]):
            fx += acc[c, i, 0]
            fy += acc[c, i, 1]
            t += acc[c, i, 2]
        f[i, 0] += fx
        f[i, 1] += fy
        tq[i] += t


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
def kick_drift(x, v, w, m, inertia, f, tq, gravity, dt, drag, v_cap, a_prev):
    """One symplectic Euler step from forces f (n, 2), torques tq (n,): kick v, w; drift x.

    Records the accelerations in a_prev (n, 3) for the next force evaluation.
    """
    damp = 1.0 / (1.0 + drag * dt)
    for i in prange(x.shape[0]):
        _kick_drift_one(
            i, x, v, w, m, inertia, f[i, 0], f[i, 1], tq[i], gravity, dt, damp, v_cap, a_prev
        )


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
    gravity,
    dt,
    drag,
    v_cap,
    acc,
    f,
    tq,
    x_ref,
    disp,
):
    """Fused per-granule pass: wall forces, sum of chunks, kick-drift, displacement² since build.

    Writes the step's total contact force and torque to f and tq; disp[c] = (max displacement²,
    max speed²) of chunk c (a per-chunk max instead of a shared reduction variable).
    """
    n = x.shape[0]
    n_chunks = acc.shape[0]
    damp = 1.0 / (1.0 + drag * dt)
    for c in prange(n_chunks):
        lo = c * n // n_chunks
        hi = (c + 1) * n // n_chunks
        dmax = 0.0
        smax = 0.0
        for i in range(lo, hi):
            fx, fy, t = wall_force(
                i, x, v, w, a_prev, r, m, inertia, mat, params, walls, wall_hist, dt
            )
            for q in range(n_chunks):
                fx += acc[q, i, 0]
                fy += acc[q, i, 1]
                t += acc[q, i, 2]
            f[i, 0] = fx
            f[i, 1] = fy
            tq[i] = t
            _kick_drift_one(i, x, v, w, m, inertia, fx, fy, t, gravity, dt, damp, v_cap, a_prev)
            ex = x[i, 0] - x_ref[i, 0]
            ey = x[i, 1] - x_ref[i, 1]
            dmax = max(dmax, ex * ex + ey * ey)
            smax = max(smax, v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
        disp[c, 0] = dmax
        disp[c, 1] = smax


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
):
    """Advance n_steps symplectic Euler steps; returns (start, nbr, hist, n_rebuilds).

    Rebuilds the neighbour list (carrying the tangential history over) before a step when
    2·(largest displacement since the last build) + dt·(largest speed) exceeds the skin (the
    dt·v term keeps listed every pair that ``touching`` may need half a step before first
    contact), when start is not a list for
    these n granules, or when rebuild is True; x_ref (n, 2) holds the positions at the last
    build and is updated in place. On return f and tq hold the contact forces and torques of
    the last step and a_prev its accelerations.
    """
    n = x.shape[0]
    n_chunks = acc.shape[0]
    disp = np.zeros((n_chunks, 2))
    half2 = 0.25 * skin * skin
    n_rebuilds = 0
    need = rebuild or start.shape[0] != n + 1
    if not need:
        for i in range(n):
            ex = x[i, 0] - x_ref[i, 0]
            ey = x[i, 1] - x_ref[i, 1]
            if ex * ex + ey * ey > half2:
                need = True
                break
    for _ in range(n_steps):
        if need:
            start, nbr, hist = build(x, r, skin, start, nbr, hist)
            x_ref[:, :] = x
            n_rebuilds += 1
        pair_forces(x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, acc)
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
            gravity,
            dt,
            drag,
            v_cap,
            acc,
            f,
            tq,
            x_ref,
            disp,
        )
        dmax = 0.0
        smax = 0.0
        for c in range(n_chunks):
            dmax = max(dmax, disp[c, 0])
            smax = max(smax, disp[c, 1])
        need = 2.0 * math.sqrt(dmax) + dt * math.sqrt(smax) > skin
    return start, nbr, hist, n_rebuilds


def new_accumulator(n_chunks: int, n: int) -> np.ndarray:
    """Per-chunk force accumulator (n_chunks, n, 3) for ``pair_forces`` and ``advance``."""
    return np.zeros((max(int(n_chunks), 1), n, 3))
