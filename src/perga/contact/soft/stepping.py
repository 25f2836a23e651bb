"""One granule's symplectic Euler step, the arithmetic the kernel's per-granule pass and the
coasting granules (``perga.contact.soft.coasting``) share, so that both give the same floats.

Symplectic Euler with velocity kicks (Hairer, Lubich & Wanner, Geometric Numerical
Integration, 2006, ch. I): v += (f/m + g) dt, w += (tq/I) dt, x += v dt with the new v; an
optional implicit drag v ← v/(1 + drag·dt) (the factor damp) and a speed cap v_cap serve
``SoftGranules.relax`` only. Arrays as in ``kernel.Granules`` and ``kernel.GranuleProps``. Every
function is inlined into its caller, whose compile flags then apply.
"""

import math

from numba import njit

from perga.geometry.disc_polygon import FASTMATH


@njit(cache=True, inline="always", fastmath=FASTMATH)
def add_pair_forces(acc, i, fx, fy, t, single):
    """(fx, fy, t) plus granule i's pair force and torque from each chunk of acc (n_chunks, n,
    3), in chunk order; zeroes those rows for the next pair pass. single (acc holds one chunk:
    one thread) adds it without the loop over chunks; given as a constant, the per-granule loop
    compiles tighter (docs/dev/performance.md)."""
    if single:
        fx += acc[0, i, 0]
        fy += acc[0, i, 1]
        t += acc[0, i, 2]
        acc[0, i, 0] = 0.0
        acc[0, i, 1] = 0.0
        acc[0, i, 2] = 0.0
        return fx, fy, t
    for q in range(acc.shape[0]):
        fx += acc[q, i, 0]
        fy += acc[q, i, 1]
        t += acc[q, i, 2]
        acc[q, i, 0] = 0.0
        acc[q, i, 1] = 0.0
        acc[q, i, 2] = 0.0
    return fx, fy, t


@njit(cache=True, inline="always", fastmath=FASTMATH)
def accelerations(i, m, inertia, fx, fy, t, gravity):
    """Granule i's accelerations (a_x, a_y), m/s², and α, rad/s², from its force (fx, fy), N,
    torque t, N·m, and gravity (2,), m/s²."""
    return fx / m[i] + gravity[0], fy / m[i] + gravity[1], t / inertia[i]


@njit(cache=True, inline="always", fastmath=FASTMATH)
def kick_drift(px, py, vx, vy, wi, ax, ay, alpha, dt, damp, v_cap):
    """One step of a granule at (px, py), m, with velocity (vx, vy), m/s, and angular velocity
    wi, rad/s, under the accelerations (ax, ay), m/s², and alpha, rad/s² (``accelerations``),
    with the velocity factor damp = 1/(1 + drag·dt) and the speed cap v_cap, m/s: the new
    (px, py, vx, vy, wi)."""
    vx = (vx + dt * ax) * damp
    vy = (vy + dt * ay) * damp
    s2 = vx * vx + vy * vy
    if s2 > v_cap * v_cap:
        scale = v_cap / math.sqrt(s2)
        vx *= scale
        vy *= scale
    wi = (wi + dt * alpha) * damp
    return px + dt * vx, py + dt * vy, vx, vy, wi


@njit(cache=True, inline="always", fastmath=FASTMATH)
def store(i, x, v, w, a_prev, px, py, vx, vy, wi, ax, ay, alpha):
    """Write granule i's position (px, py), velocity (vx, vy), angular velocity wi and
    accelerations (ax, ay, alpha) into the arrays."""
    x[i, 0] = px
    x[i, 1] = py
    v[i, 0] = vx
    v[i, 1] = vy
    w[i] = wi
    a_prev[i, 0] = ax
    a_prev[i, 1] = ay
    a_prev[i, 2] = alpha


@njit(cache=True, inline="always", fastmath=FASTMATH)
def kick_drift_one(i, x, v, w, m, inertia, fx, fy, t, gravity, dt, damp, v_cap, a_prev):
    """``kick_drift`` for granule i of the arrays from its force (fx, fy), N, and torque t,
    N·m; records a_prev[i]."""
    ax, ay, alpha = accelerations(i, m, inertia, fx, fy, t, gravity)
    px, py, vx, vy, wi = kick_drift(
        x[i, 0], x[i, 1], v[i, 0], v[i, 1], w[i], ax, ay, alpha, dt, damp, v_cap
    )
    store(i, x, v, w, a_prev, px, py, vx, vy, wi, ax, ay, alpha)


@njit(cache=True, inline="always", fastmath=FASTMATH)
def motion(px, py, vx, vy, ax, ay, rx, ry, h):
    """A granule's |x − x_ref|² (m²), |v|² and |v + h a_prev|² (m²/s²) from its position
    (px, py), velocity (vx, vy), accelerations (ax, ay) and list position (rx, ry); h = dt/2."""
    ex = px - rx
    ey = py - ry
    ux = vx + h * ax
    uy = vy + h * ay
    return ex * ex + ey * ey, vx * vx + vy * vy, ux * ux + uy * uy


@njit(cache=True, inline="always", fastmath=FASTMATH)
def motion_of(i, x, v, a_prev, x_ref, h):
    """``motion`` of granule i of the arrays."""
    return motion(
        x[i, 0], x[i, 1], v[i, 0], v[i, 1], a_prev[i, 0], a_prev[i, 1], x_ref[i, 0], x_ref[i, 1],
        h,
    )  # fmt: skip
