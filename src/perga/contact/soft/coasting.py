"""Coasting granules: the granules no contact can reach for the rest of a kernel call take
all of its steps at once, with the same floats as step by step (docs/dev/performance.md).

A granule coasts from step k0 of a call for the S steps left when

* ``kernel.mark_special`` did not flag it (no wall within reach, no polygon candidate, no
  bond), and
* every pair of the neighbour list it is in holds no tangential spring and is farther apart
  than r_i + r_j + S·dt·(b_i + b_j) + dt·V (``coast``). V is the call's speed bound
  (``speed_bound``): twice the largest speed and extrapolated speed |v + ½ dt a_prev| of any
  granule at k0, plus |g|·(S + 1)·dt. b_i is granule i's own bound: V for a flagged granule
  (a hammer or a wall may strike it), else twice the largest speed or extrapolated speed of i
  and of its list partners, plus the same gravity term (b_i ≤ V).

While every granule that does not coast keeps |v| and |v + ½ dt a_prev| within its bound (the
kernel checks it after every step: V for all of them, b_j for the unflagged, ``outruns``), a
coasting granule moves at most S·dt·b_i and each of its partners at most S·dt·b_j; the pair
pass reads them at most that far ahead of where they are, and a pair's reach
(``kernel.pair_force``) is at most dt·V. So no pair of it comes within r_i + r_j + reach: the
pair pass adds nothing for it, as step by step, and its only force is gravity. Its steps are the
free path's arithmetic with zero pair forces (``stepping``), taken at once (``coast``): its
accelerations once, its state in registers, its displacement, speed and extrapolated speed after
each step recorded, so that the call's rebuild test and reach see the maxima they see step by
step. With one bound V for all, the granules of a separator resting beside each other on the
rotor could not coast while a struck granule flew elsewhere; with their own they can.

The kernel rewinds the coasting granules to the step reached (``rewind``: their state at k0
saved, those steps taken again) wherever the premise may fail: before a rebuild of the
neighbour list, before the granules are flagged anew, and after a step in which a granule that
does not coast went faster than V; the rest of the call then decides anew.
"""

import math

import numpy as np
from numba import njit

from perga.contact.soft.stepping import (
    accelerations,
    add_pair_forces,
    kick_drift,
    motion,
    motion_of,
    store,
)
from perga.geometry.disc_polygon import FASTMATH

COAST = 2
"""The value of a coasting granule in the flags of ``kernel.mark_special`` (0 free, 1 flagged)."""


@njit(cache=True, fastmath=FASTMATH)
def speed_bound(smax, umax, gravity, steps, dt):
    """V, m/s (module doc), from the largest speed² smax and extrapolated speed² umax of the
    granules (m²/s²), gravity (2,) (m/s²) and the steps left, each of dt (s)."""
    g = math.sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1])
    return 2.0 * math.sqrt(max(smax, umax)) + g * (steps + 1) * dt


@njit(cache=True, fastmath=FASTMATH)
def coast(granules, props, acc, f, tq, x_ref, nbrs, flags, scalars, maxima, bound):
    """Take the S steps left at once for every granule that may coast (module doc): marks it
    COAST in flags (n,) int8, writes its contact force and torque (zero) to f and tq, each
    granule's own speed bound b_i (m/s) to bound (n,), and the largest |x − x_ref|², |v|² and
    |v + ½ dt a_prev|² of the coasting granules after each step to maxima[:S] (S, 3); returns,
    for ``rewind``, their indices (count,) int64, their x, y, vx, vy, w before (5, count) and
    their accelerations a_x, a_y, α (3, count), and the indices of the granules left unflagged
    (flags 0: the free path's list), each in increasing order.

    granules, props: as in ``kernel.Granules`` and ``kernel.GranuleProps``; acc, f, tq as in
    ``kernel.Work``; nbrs = (start, nbr, hist) the half list (another length of start: no
    pairs); scalars = (S, dt, gravity, damp, v_cap, V). A pair holding a tangential spring
    stops both from coasting whatever its distance (the pair pass must release the spring)."""
    x, v, w, a_prev = granules
    r, m, inertia = props.r, props.m, props.inertia
    start, nbr, hist = nbrs
    steps, dt, gravity, damp, v_cap, speed = scalars
    n = x.shape[0]
    pairs = start.shape[0] == n + 1  # else no list: no pairs
    fastest = np.empty(n)  # each granule's largest speed² or extrapolated speed²
    for i in range(n):
        _, s2, u2 = motion_of(i, x, v, a_prev, x, 0.5 * dt)
        fastest[i] = max(s2, u2)
    local = fastest.copy()  # and its partners'
    for i in range(n if pairs else 0):
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            local[i] = max(local[i], fastest[j])
            local[j] = max(local[j], fastest[i])
    fall = math.sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1]) * (steps + 1) * dt
    for i in range(n):
        bound[i] = speed if flags[i] != 0 else min(2.0 * math.sqrt(local[i]) + fall, speed)
    near = flags != 0
    ahead = steps * dt * (1.0 + 1e-9)
    reach = dt * speed * (1.0 + 1e-9)
    for i in range(n if pairs else 0):
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            dx = x[i, 0] - x[j, 0]
            dy = x[i, 1] - x[j, 1]
            keep = r[i] + r[j] + ahead * (bound[i] + bound[j]) + reach
            if hist[k] != 0.0 or dx * dx + dy * dy <= keep * keep:
                near[i] = True
                near[j] = True
    index = np.empty(n, np.int64)
    free = np.empty(n, np.int64)
    count = 0
    n_free = 0
    for i in range(n):
        if not near[i]:
            index[count] = i
            count += 1
        elif flags[i] == 0:
            free[n_free] = i
            n_free += 1
    index = index[:count]
    state = np.empty((10, count))  # x, y, vx, vy, w, a_x, a_y, α, and x_ref's x, y
    for c in range(count):
        i = index[c]
        flags[i] = COAST
        fx, fy, t = add_pair_forces(acc, i, 0.0, 0.0, 0.0, acc.shape[0] == 1)
        f[i, 0] = fx
        f[i, 1] = fy
        tq[i] = t
        ax, ay, alpha = accelerations(i, m, inertia, fx, fy, t, gravity)
        state[0, c] = x[i, 0]
        state[1, c] = x[i, 1]
        state[2, c] = v[i, 0]
        state[3, c] = v[i, 1]
        state[4, c] = w[i]
        state[5, c] = ax
        state[6, c] = ay
        state[7, c] = alpha
        state[8, c] = x_ref[i, 0]
        state[9, c] = x_ref[i, 1]
    saved = state[:5].copy()
    if v_cap == math.inf:  # a literal infinite cap: the compiler drops the cap's test
        unforced = gravity[0] == 0.0 and gravity[1] == 0.0 and damp == 1.0
        _steps(state, steps, dt, damp, math.inf, maxima, unforced)
    else:
        _steps(state, steps, dt, damp, v_cap, maxima, False)
    for c in range(count):
        i = index[c]
        px, py, vx, vy, wi = state[0, c], state[1, c], state[2, c], state[3, c], state[4, c]
        store(i, x, v, w, a_prev, px, py, vx, vy, wi, state[5, c], state[6, c], state[7, c])
    return (index, saved, state[5:8].copy()), free[:n_free]


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _steps(state, steps, dt, damp, v_cap, maxima, unforced):
    """``steps`` steps of the granules of state (``coast``), each over all of them (loops the
    compiler vectorises); the largest |x − x_ref|², |v|², |v + ½ dt a|² after each step to
    maxima. None is negative, so the largest is found on their bits as integers (the same
    order; a loop over floats the compiler would not vectorise).

    unforced: no acceleration, no drag, no cap. After the first step, which turns a −0
    velocity into +0, the velocities are then constant to the bit ((v + dt·0)·1 = v), and so
    are the speeds: the steps after it only drift."""
    count = state.shape[1]
    px, py, vx, vy, wi = state[0], state[1], state[2], state[3], state[4]
    ax, ay, alpha, rx, ry = state[5], state[6], state[7], state[8], state[9]
    moved = np.empty((3, count))
    largest = maxima.view(np.int64)
    bits = moved.view(np.int64)
    h = 0.5 * dt
    for s in range(steps):
        if unforced and s > 0:
            for c in range(count):
                px[c] = px[c] + dt * vx[c]
                py[c] = py[c] + dt * vy[c]
                ex = px[c] - rx[c]
                ey = py[c] - ry[c]
                moved[0, c] = ex * ex + ey * ey
            maxima[s, 1] = maxima[0, 1]
            maxima[s, 2] = maxima[0, 2]
            largest[s, 0] = _largest(bits[0])
            continue
        for c in range(count):
            px[c], py[c], vx[c], vy[c], wi[c] = kick_drift(
                px[c], py[c], vx[c], vy[c], wi[c], ax[c], ay[c], alpha[c], dt, damp, v_cap
            )
            moved[0, c], moved[1, c], moved[2, c] = motion(
                px[c], py[c], vx[c], vy[c], ax[c], ay[c], rx[c], ry[c], h
            )
        for q in range(3):
            largest[s, q] = _largest(bits[q])


@njit(cache=True, inline="always")
def _largest(bits):
    """The largest of bits (n,) int64, 0 for none."""
    top = 0
    for b in bits:
        top = max(top, b)
    return top


@njit(cache=True, fastmath=FASTMATH)
def rewind(granules, flags, coasting, scalars):
    """Put the coasting granules (index, saved x, y, vx, vy, w and their accelerations) =
    coasting (``coast``) where their first ``steps`` (≥ 1) steps take them and clear their
    flags; scalars = (steps, dt, damp, v_cap)."""
    x, v, w, a_prev = granules
    index, saved, accel = coasting
    steps, dt, damp, v_cap = scalars
    for c in range(index.shape[0]):
        i = index[c]
        flags[i] = 0
        px, py, vx, vy, wi = saved[0, c], saved[1, c], saved[2, c], saved[3, c], saved[4, c]
        ax, ay, alpha = accel[0, c], accel[1, c], accel[2, c]
        for _ in range(steps):
            px, py, vx, vy, wi = kick_drift(px, py, vx, vy, wi, ax, ay, alpha, dt, damp, v_cap)
        store(i, x, v, w, a_prev, px, py, vx, vy, wi, ax, ay, alpha)


@njit(cache=True, fastmath=FASTMATH)
def outruns(v, a_prev, free, bound, h):
    """Whether a granule of ``free`` (the unflagged granules that do not coast) has a speed or
    extrapolated speed |v + h a_prev| (m/s) above its bound (``coast``); h = dt/2, s."""
    for i in free:
        b2 = bound[i] * bound[i]
        ux = v[i, 0] + h * a_prev[i, 0]
        uy = v[i, 1] + h * a_prev[i, 1]
        if v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] > b2 or ux * ux + uy * uy > b2:
            return True
    return False
