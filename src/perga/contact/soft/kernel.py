"""Compiled soft-granule kernel: pair and wall forces, symplectic Euler, k steps inside numba.

Arrays (SI, float64 unless said, C-contiguous) come in named bundles (``typing.NamedTuple``,
which numba compiles as tuples with attribute access):

* ``Granules``: positions x (n, 2), velocities v (n, 2), angular velocities w (n,) and the
  accelerations a_prev (n, 3) = (a_x, a_y, α) of the last step;
* ``GranuleProps``: radii r (n,), masses m (n,), moments of inertia about the centre (n,)
  (m r²/2 for a disc) and materials mat (n,) int32;
* ``Bonds``: the comb's hold on each granule: held (n,) int8, bond_force (n,) N,
  bond_energy (n,) J, and what the kernel writes at a release, released_step (n,) int64 and
  release_force (n,) N;
* ``params``: the pair table (n_mat, n_mat, N_PARAMS) of ``perga.contact.soft.laws``;
* ``Walls``: rows (n_walls, 6) and the tangential history hist (n, n_walls), below;
* ``Polygons``: ``PolygonArrays``, ``TableArrays``, the contact history (n, n_poly,
  ``HIST_COLUMNS``) and ``PolygonLoads`` (``perga.contact.soft.polygon_set``), and the candidate
  list kept from the last call (``CandidateList``), empty arrays for no polygons;
* ``NeighbourList``: the half list start, nbr, hist (``perga.contact.soft.neighbours``) and the
  positions x_ref (n, 2) it was built at;
* ``Work``: the per-chunk force accumulator acc (n_chunks, n, 3), the contact forces f (n, 2)
  and torques tq (n,) of the last step, the dissipated energies (3,) and the event counts (2,);
* ``Settings``: n_steps, dt (s), gravity (2,) m/s², skin (m), drag (1/s), v_cap (m/s), pairs,
  rebuild, first_step (the count of steps before the call);
* ``Opening``: what a call does before its first step: the floor-friction kick the effects
  handed over (``perga.machine.effects.FloorKick``) and the copy of the state after it that the
  impact log keeps (``perga.contact.soft.impacts``), each optional.

Bonds (the comb, ``perga.model.process``): a held granule (held = 1) stays where it is, at rest,
while the force its bond must take, F = |f + m g| (f the contact force of the step, g gravity),
is at most its bond_force. In the first step where it is larger, with no bond_energy (inf), the
bond breaks (held = 0, released_step the step's number, release_force F) and the granule moves
under that force. With a bond_energy E_c the step begins a blow instead (held = 2,
release_force F), unless the bond cannot carry the granule's weight (m|g| > bond_force: it
breaks at once): the granule moves freely, of its own mass, until its contact force is zero
again; then, if its kinetic energy E (translation and spin) exceeds E_c, the bond breaks and
the granule goes on with its velocities scaled by √(1 − E_c/E) (the bond took E_c), else it
stops where it is (held = 1) and the bond took E. Either way the bond's share is booked with
the walls' dissipation (the cell is a contact). A blow's outcome is then the impact law's (the
same free granule struck), whatever the contact's stiffness or the step.

Walls: rows ``[kind, a, b, c, d, mat]``:

* kind WALL_CHAMBER: round chamber, centre (a, b), inner radius c; the granule is inside;
* kind WALL_PLANE: half-plane through (a, b) with unit normal (c, d) pointing into the domain.

A wall is a body of infinite mass at rest: its contacts use m_eff = m_i (and I_i for rolling).
A granule's walls are evaluated only while it can reach one: its gap to the nearest at the
list's build positions (``wall_gaps``, at a call's first step and after every rebuild) is at
most its largest displacement since plus the reach (``pair_force``).

Integrator: symplectic Euler with velocity kicks (Hairer, Lubich & Wanner, Geometric Numerical
Integration, 2006, ch. I; ``perga.contact.soft.stepping``): forces from (x, v, w) at step
start, then v += (f/m + g) dt, w += tq/I dt, x += v dt with the new v. Optional global drag
(implicit: v ← v/(1 + drag·dt)) and a speed cap v_cap serve ``SoftGranules.relax`` only;
normal runs have drag = 0,
v_cap = inf.

Polygons (hammers, ``perga.contact.soft.polygon_forces``): during a call of n steps each polygon
moves rigidly from its pose at the call's first force evaluation, the PINNED pivot moving with
it, and its body takes the granules' forces as they do: after each step's force evaluation the
FREE and PINNED bodies are kicked by that step's loads (``polygon_forces.kick_bodies``) and
drift on at their new velocities (``polygon_forces.pose`` from the pose of the last kick), so a
hammer stopped by a granule recoils within the call, at the granules' step. After the call the
polygons hold the pose n·dt later (the granules' time) and their velocities as they came in;
the loads are the means over the call, and ``recoil`` how far the kicks of all steps but the
last moved each body beyond its drift at those velocities: a machine step that drifts the
body at its start velocities, adds the recoil and then kicks it by the mean loads follows the
call exactly (a multiple-time-step split, as r-RESPA: Tuckerman, Berne & Martyna, J. Chem.
Phys. 97, 1990 (1992)). With n = 1 nothing differs from a body at fixed velocities.

Contacts with polygons are evaluated for a candidate list (``polygon_forces.candidates``), so
that granules far from every polygon cost nothing per step; it is built after every
neighbour-list rebuild with a margin of ``CANDIDATE_MARGIN`` skins, and the calls after keep it
while the polygons stay within that margin (``advance``; checked again after a kick).

Per-granule pass (``_integrate``): the granules that can reach a wall, have polygon candidates
or are held (``mark_special``: at a call's first step, after every rebuild, and when the walls'
reach ``near`` has grown ``SPECIAL_MARGIN`` skins past its value then) take the full path;
every other granule only sums its pair forces and moves, in a loop compiled on its own
(``_integrate_free``). A granule's step touches only its own state, so the split changes no
float. The granules that no contact can reach for the rest of the call coast
(``perga.contact.soft.coasting``): they take those steps at once after the flagging, the
passes skip them, and they are rewound to the step reached wherever that may no longer hold;
the floats are those of steps one by one.

Dissipation: every contact reports the energy its law dissipated over the step
(``laws.contact_force``; rolling resistance |M ω_rel| dt; a tangential spring dropped at a
contact's end ½ k_t ξ²); ``Work.dissipated`` accumulates [granule pairs, walls, polygons], J.

Parallel loops: the bundles are unpacked into arrays before every ``prange`` loop (and
``pair_forces``, the hottest, takes arrays), and the per-contact functions called inside it
(``pair_force``, ``wall_force``, ``stepping.kick_drift_one``,
``polygon_forces.polygon_contact``) take the granule arrays themselves. Numba (0.68) drops
writes made through a named tuple's field inside a parallel loop (numba issues #5872, #7135),
and reading the granule arrays through a bundle there changed the compiled fast-math
arithmetic in the last bit; polygon and table bundles, only read there, are passed whole.

Threads: pair forces are split in ``n_chunks`` contiguous ranges of i, each accumulating into
its own slice of ``acc``, summed per granule afterwards in chunk order, so each pair is computed
once and no two threads write the same memory (no races). The chunks fix every sum's order, so
the results depend on n_chunks and never on the threads (``perga.contact.soft.threads``).
``advance_threaded`` computes the chunks on numba's threads; ``advance``, on one thread, takes
them one after the other in functions without a parallel region (``_pair_forces_serial``,
``_integrate_serial``), with the same arithmetic: opening a region costs microseconds per step
even on one thread, which a small system pays many times over. Both share one body
(``_advance``, inlined), so each compiles only its own passes (docs/dev/performance.md).
Everything else is per granule; polygon loads and their dissipation are summed per
candidate entry in a fixed order afterwards, so they and the granules' polygon forces do not
depend on the number of threads.
"""

import math
import warnings
from typing import NamedTuple

import numpy as np
from numba import njit, prange
from numba.core.errors import NumbaPerformanceWarning

from perga.contact.soft.coasting import COAST, coast, outruns, rewind, speed_bound
from perga.contact.soft.laws import (
    LINEAR,
    P_CLAMP,
    P_DAMP,
    P_DAMPT,
    P_HERTZ,
    P_MU,
    P_MUR,
    contact_law,
    contact_stiffness,
    form,
    normal_force,
    released,
    rolling_torque,
    touching,
)
from perga.contact.soft.neighbours import build
from perga.contact.soft.polygon_forces import (
    CANDIDATE_MARGIN,
    Candidates,
    Pose,
    add_loads,
    add_recoil,
    candidate_reach,
    candidates,
    candidates_hold,
    kick_bodies,
    polygon_contact,
    pose,
)
from perga.contact.soft.polygon_set import HIST_ACTIVE, PolygonArrays, PolygonLoads, TableArrays
from perga.contact.soft.stepping import add_pair_forces, kick_drift_one, motion_of
from perga.geometry.disc_polygon import FASTMATH, bounding_radii
from perga.machine.effects import floor_kick

# ``_pair_forces_serial`` and ``_integrate_serial`` hold no prange but are compiled as the
# parallel loops' bodies are (parallel=True, error_model="numpy"): without parallel=True numba
# compiles the same loops to slower code (docs/dev/performance.md), and with numba's error
# model of parallel regions their arithmetic is the same bit for bit (one thread then agrees
# with two where the sums do not depend on the thread count). Numba warns that nothing could be
# parallelised.
warnings.filterwarnings(
    "ignore",
    message=r"\s*The keyword argument 'parallel=True' was specified but no transformation",
    category=NumbaPerformanceWarning,
)

WALL_CHAMBER = 0
WALL_PLANE = 1
WALL_COLUMNS = 6

DISSIPATED_PAIRS, DISSIPATED_WALLS, DISSIPATED_POLYGONS = 0, 1, 2
"""Entries of the (3,) dissipated-energy totals ``Work.dissipated``, J."""
COUNT_CONTACT_CHANGES, COUNT_RELEASES = 0, 1
"""Entries of the (2,) running counts ``Work.counts``: granule-polygon contacts opened or
closed (a contact's ``HIST_ACTIVE`` flag changed), granules released from their bonds."""
SPECIAL_MARGIN = 0.5
"""The wall distance the flagged granules of ``mark_special`` cover beyond the call's current
``near``, in skins: they are flagged again only when ``near`` grows past it."""


class Granules(NamedTuple):
    """Granule state: x (n, 2), m; v (n, 2), m/s; w (n,), rad/s; a_prev (n, 3): the last
    step's accelerations (a_x, a_y) m/s² and α rad/s²."""

    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    a_prev: np.ndarray


class GranuleProps(NamedTuple):
    """Granule constants: r (n,), m; m (n,), kg; inertia (n,), kg·m²; mat (n,) int32."""

    r: np.ndarray
    m: np.ndarray
    inertia: np.ndarray
    mat: np.ndarray


class Bonds(NamedTuple):
    """The comb's bonds (module doc): held (n,) int8 (1: held, 2: in a blow); bond_force (n,),
    N; bond_energy (n,), J (inf: none); released_step (n,) int64 (−1 until released);
    release_force (n,), N (nan until released)."""

    held: np.ndarray
    bond_force: np.ndarray
    bond_energy: np.ndarray
    released_step: np.ndarray
    release_force: np.ndarray


class Walls(NamedTuple):
    """Walls: rows (n_walls, WALL_COLUMNS) (module doc); hist (n, n_walls): tangential spring
    ξ of each granule-wall contact, m."""

    rows: np.ndarray
    hist: np.ndarray


class CandidateList(NamedTuple):
    """A polygon candidate list kept from call to call (``polygon_forces.candidates``): start
    (n + 1,) int64 (another length: none kept) and polygon (entries,) int64, as in
    ``Candidates``; vertices (n_vertices, 2), m, the polygons' vertices when it was built, and
    reach (n_poly,), m, the reach it was built with (``candidate_reach``), both written in
    place."""

    start: np.ndarray
    polygon: np.ndarray
    vertices: np.ndarray
    reach: np.ndarray


class Polygons(NamedTuple):
    """Polygons for the kernel: arrays (``PolygonArrays``, posed in place during a call), table
    (``TableArrays``), hist (n, n_poly, ``HIST_COLUMNS``) the contact history, loads
    (``PolygonLoads``) the mean loads over a call, listed (``CandidateList``) the candidate
    list the last call left."""

    arrays: PolygonArrays
    table: TableArrays
    hist: np.ndarray
    loads: PolygonLoads
    listed: CandidateList


class NeighbourList(NamedTuple):
    """Verlet half list (``perga.contact.soft.neighbours``): start (n + 1,) int64, nbr int64,
    hist (tangential spring ξ per entry, m), and x_ref (n, 2), the positions at its build, m."""

    start: np.ndarray
    nbr: np.ndarray
    hist: np.ndarray
    x_ref: np.ndarray


class Work(NamedTuple):
    """Arrays the kernel writes: acc (n_chunks, n, 3) per-chunk pair forces and torques (N, N·m;
    ``new_accumulator``); f (n, 2), N, and tq (n,), N·m: the last step's contact forces and
    torques; dissipated (3,): energy dissipated, J, added to (``DISSIPATED_*``); counts (2,)
    int64: contact changes and releases, added to (``COUNT_*``)."""

    acc: np.ndarray
    f: np.ndarray
    tq: np.ndarray
    dissipated: np.ndarray
    counts: np.ndarray


class Settings(NamedTuple):
    """The call's scalars: n_steps; dt, s; gravity (2,), m/s²; skin, m; drag, 1/s; v_cap, m/s;
    pairs: granule-granule contacts on; rebuild: rebuild the neighbour list first; first_step:
    the number of steps taken before the call; coast: let the granules out of every contact's
    reach take their steps at once (``perga.contact.soft.coasting``)."""

    n_steps: int
    dt: float
    gravity: np.ndarray
    skin: float
    drag: float
    v_cap: float
    pairs: bool
    rebuild: bool
    first_step: int
    coast: bool


class Opening(NamedTuple):
    """What a call does before its first step. The floor-friction kick if energy has two
    entries (``perga.machine.effects.floor_kick`` on the granules, dv_max in m/s and omega in
    rad/s; corotating False: the velocities stand for the positions, as the effects' runner
    gives them), its removed and supplied energy added to energy (J) in place; then, if keep,
    the granules' x, v, w and the polygons' vertices and com copied into kept (arrays of their
    shapes)."""

    dv_max: float
    omega: float
    corotating: bool
    energy: np.ndarray
    keep: bool
    kept: tuple


@njit(cache=True, inline="always", fastmath=FASTMATH)
def pair_force(
    i, j, k, dx, dy, d2, rs, far, v, w, a_prev, r, m, inertia, mat, params, hist, dt, tangential,
    rolling, linear,
):  # fmt: skip
    """Force (fx, fy) on i (−it on j), torques on i and j, dissipated energy (J), for list entry
    k; updates hist[k].

    dx, dy = x_i − x_j and d2 = dx² + dy², m and m²; rs = r_i + r_j, m; far = rs + reach, m,
    reach being dt times the largest extrapolated speed |v + ½ dt a_prev| of any granule, a
    bound of the gap a pair can close in half a step (½ dt |δ̇|). A pair farther apart than far
    is not ``touching``; ``_pair_range`` skips it unless it holds a spring, which is dropped
    here before the velocities are read. tangential: whether any pair of the table has friction
    or tangential damping; if not, the tangential law is skipped (its force is zero and its
    spring stays empty). rolling: whether any pair of the table has rolling resistance; if so,
    it is computed for a pair with μ_r > 0 (a flag for the whole table lets the compiler drop the
    per-pair test where nothing rolls, docs/dev/performance.md). linear: the table holds linear
    rows only (``laws.form``)."""
    h = 0.5 * dt
    a = mat[i]
    b = mat[j]
    hertz = form(params, a, b, linear)
    if d2 > far * far:
        xi = hist[k]
        hist[k] = 0.0
        gap = rs - math.sqrt(d2)
        return 0.0, 0.0, 0.0, 0.0, released(params, a, b, r[i] * r[j] / rs, gap, xi, hertz)
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
    ddelta = -(vrx * nx + vry * ny)
    delta = rs - d
    if not touching(delta, ddelta, dt):
        xi = hist[k]
        if xi == 0.0:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        hist[k] = 0.0
        return 0.0, 0.0, 0.0, 0.0, released(params, a, b, r[i] * r[j] / rs, delta, xi, hertz)
    r_eff = r[i] * r[j] / rs
    m_eff = m[i] * m[j] / (m[i] + m[j])
    wi = w[i] + h * a_prev[i, 2]
    wj = w[j] + h * a_prev[j, 2]
    if tangential:
        tx = -ny
        ty = nx
        # Lever arms to the middle of the overlap, or of the gap just before first touch: they
        # sum to d, so both discs load one common point and angular momentum is conserved.
        half = 0.5 * delta
        arm_i = r[i] - half
        arm_j = r[j] - half
        vt = vrx * tx + vry * ty - (arm_i * wi + arm_j * wj)
        fn, ft, hist[k], lost = contact_law(
            params, a, b, hertz, r_eff, delta, ddelta, vt, m_eff, hist[k], dt
        )
        fx = fn * nx + ft * tx
        fy = fn * ny + ft * ty
        ti = -arm_i * ft
        tj = -arm_j * ft
    else:
        fn, lost = normal_force(
            contact_stiffness(params, a, b, r_eff, hertz), params[a, b, P_DAMP], hertz,
            params[a, b, P_CLAMP], delta, ddelta, m_eff, dt,
        )  # fmt: skip
        xi = hist[k]
        if xi != 0.0:
            hist[k] = 0.0
            lost += released(params, a, b, r_eff, delta, xi, hertz)
        fx = fn * nx
        fy = fn * ny
        ti = 0.0
        tj = 0.0
    if rolling and params[a, b, P_MUR] != 0.0:  # rolling resistance
        i_red = inertia[i] * inertia[j] / (inertia[i] + inertia[j])
        mr = rolling_torque(params, a, b, fn, wi - wj, r_eff, i_red, dt)
        if mr != 0.0:
            lost += abs(mr * (wi - wj)) * dt
            ti += mr
            tj -= mr
    return fx, fy, ti, tj, lost


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _pair_range(
    lo, hi, x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, tangential,
    rolling, linear, out, flags,
):  # fmt: skip
    """Pair forces of the list rows lo:hi (granules i) added into out (n, 3) = (fx, fy, torque),
    which holds zeros (the per-granule pass zeroes each row it reads); returns the energy those
    contacts dissipated, J. Arguments as in ``pair_forces``. A pair farther apart than r_i + r_j +
    reach that holds no spring has no force and nothing to release: it is skipped before
    ``pair_force``, whose zeros would otherwise be added. Numba wraps a negative index around unless
    the compiler can prove it non-negative, so i starts at max(lo, 0) and an entry j < 0 (there is
    none) is skipped: the wraparound is then dropped from every index below
    (docs/dev/performance.md). The row of a granule flagged ``coasting.COAST`` in flags (n,) is
    skipped: none of its pairs can come within reach (``perga.contact.soft.coasting``)."""
    dissipated = 0.0
    for i in range(max(lo, 0), hi):
        if flags[i] == COAST:
            continue
        xi = x[i, 0]
        yi = x[i, 1]
        ri = r[i]
        for k in range(start[i], start[i + 1]):
            j = nbr[k]
            if j < 0:
                continue  # never: an index hint (doc)
            dx = xi - x[j, 0]
            dy = yi - x[j, 1]
            d2 = dx * dx + dy * dy
            rs = ri + r[j]
            far = rs + reach
            if d2 > far * far and hist[k] == 0.0:
                continue  # no force and no spring to release (``pair_force``): nothing to add
            fx, fy, ti, tj, de = pair_force(
                i, j, k, dx, dy, d2, rs, far, v, w, a_prev, r, m, inertia, mat, params, hist, dt,
                tangential, rolling, linear,
            )  # fmt: skip
            out[i, 0] += fx
            out[i, 1] += fy
            out[i, 2] += ti
            out[j, 0] -= fx
            out[j, 1] -= fy
            out[j, 2] += tj
            dissipated += de
    return dissipated


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def pair_forces(
    x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, tangential,
    rolling, linear, acc, lost, flags,
):  # fmt: skip
    """Pair forces of the list (start, nbr, hist) added into acc (n_chunks, n, 3) = (fx, fy,
    torque), which holds zeros, one slice per chunk of i, in parallel; the energy the chunk's
    contacts dissipated into lost[c], J. Arrays as in ``Granules``, ``GranuleProps`` and
    ``NeighbourList``: this loop is the kernel's hottest, and it ran slower taking the bundles
    (docs/dev/performance.md); reach (m), tangential, rolling and linear: as in ``pair_force``;
    one chunk of the common table (``_common_table``) runs ``_pair_rows``, a copy of the loop
    compiled for it, here and in ``_pair_forces_serial`` alike (the same floats on one thread
    or two); every other call runs the loop that reads the flags, and each row's form, at run
    time; flags (n,) int8:
    the rows of the granules flagged ``coasting.COAST`` are skipped (``_pair_range``). One
    chunk runs in ``_pair_forces_serial`` (no parallel region to open)."""
    n = x.shape[0]
    n_chunks = acc.shape[0]
    if _common_table(n_chunks, linear, tangential, rolling):
        lost[0] = _pair_rows(
            x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, acc, flags
        )
        return
    for c in prange(n_chunks):
        lost[c] = _pair_range(
            c * n // n_chunks, (c + 1) * n // n_chunks, x, v, w, a_prev, r, m, inertia, mat,
            params, start, nbr, hist, dt, reach, tangential, rolling, False, acc[c], flags,
        )  # fmt: skip


@njit(cache=True, parallel=True, fastmath=FASTMATH, error_model="numpy")
def _pair_forces_serial(
    x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, tangential,
    rolling, linear, acc, lost, flags,
):  # fmt: skip
    """``pair_forces`` on one thread, chunk after chunk, without a parallel region."""
    n = x.shape[0]
    n_chunks = acc.shape[0]
    if _common_table(n_chunks, linear, tangential, rolling):
        lost[0] = _pair_rows(
            x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, acc, flags
        )
        return
    for c in range(n_chunks):
        lost[c] = _pair_range(
            c * n // n_chunks, (c + 1) * n // n_chunks, x, v, w, a_prev, r, m, inertia, mat,
            params, start, nbr, hist, dt, reach, tangential, rolling, False, acc[c], flags,
        )  # fmt: skip


@njit(cache=True, inline="always")
def _common_table(n_chunks, linear, tangential, rolling):
    """Whether a pair pass runs ``_pair_rows``: one chunk, linear rows, friction (or tangential
    damping), no rolling resistance."""
    return n_chunks == 1 and linear and tangential and not rolling


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _pair_rows(
    x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, acc, flags
):
    """The pair forces of the common table (linear rows with friction, no rolling resistance)
    in one chunk (acc (1, n, 3)): ``_pair_range`` over the rows 0:n with its flags constants,
    so that the other laws' branches are not in the compiled loop, nor bounds computed from a
    chunk (both slower, docs/dev/performance.md)."""
    return _pair_range(
        0, x.shape[0], x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach,
        True, False, True, acc[0], flags,
    )  # fmt: skip


@njit(cache=True, inline="always", fastmath=FASTMATH)
def wall_force(i, x, v, w, a_prev, r, m, inertia, mat, params, rows, wall_hist, dt, reach):
    """Sum of the wall forces and torque on granule i and the energy they dissipated:
    (fx, fy, tq, J); updates wall_hist[i]. Arrays as in ``Granules``, ``GranuleProps`` and
    ``Walls``; reach, m: as in ``pair_force`` (a granule deeper inside a chamber than reach is
    rejected on its squared distance)."""
    h = 0.5 * dt
    ux = v[i, 0] + h * a_prev[i, 0]
    uy = v[i, 1] + h * a_prev[i, 1]
    wi = w[i] + h * a_prev[i, 2]
    fx = 0.0
    fy = 0.0
    tq = 0.0
    lost = 0.0
    a = mat[i]
    for s in range(rows.shape[0]):
        b = int(rows[s, 5])
        if rows[s, 0] == WALL_CHAMBER:
            dx = x[i, 0] - rows[s, 1]
            dy = x[i, 1] - rows[s, 2]
            d2 = dx * dx + dy * dy
            inside = rows[s, 3] - r[i] - reach
            if inside > 0.0 and d2 < inside * inside:
                xi = wall_hist[i, s]
                if xi != 0.0:
                    gap = r[i] + math.sqrt(d2) - rows[s, 3]
                    lost += released(params, a, b, r[i], gap, xi, params[a, b, P_HERTZ])
                    wall_hist[i, s] = 0.0
                continue
            d = math.sqrt(d2)
            delta = r[i] + d - rows[s, 3]
            if d > 0.0:
                nx = -dx / d
                ny = -dy / d
            else:
                nx = 1.0
                ny = 0.0
        else:
            nx = rows[s, 3]
            ny = rows[s, 4]
            delta = r[i] - ((x[i, 0] - rows[s, 1]) * nx + (x[i, 1] - rows[s, 2]) * ny)
        ddelta = -(ux * nx + uy * ny)
        if not touching(delta, ddelta, dt):
            xi = wall_hist[i, s]
            if xi != 0.0:
                lost += released(params, a, b, r[i], delta, xi, params[a, b, P_HERTZ])
                wall_hist[i, s] = 0.0
            continue
        tx = -ny
        ty = nx
        vt = ux * tx + uy * ty - r[i] * wi
        fn, ft, wall_hist[i, s], de = contact_law(
            params, a, b, params[a, b, P_HERTZ], r[i], delta, ddelta, vt, m[i], wall_hist[i, s], dt
        )
        fx += fn * nx + ft * tx
        fy += fn * ny + ft * ty
        if params[a, b, P_MUR] != 0.0:
            mr = rolling_torque(params, a, b, fn, wi, r[i], inertia[i], dt)
            tq += -r[i] * ft + mr
            lost += de + abs(mr * wi) * dt if mr != 0.0 else de
        else:
            tq += -r[i] * ft
            lost += de
    return fx, fy, tq, lost


@njit(cache=True, fastmath=FASTMATH)
def wall_gaps(x_ref, r, rows, wall_hist, gap):
    """Each granule's smallest gap to a wall at the positions x_ref (m; < 0 overlapping) into
    gap (n,), −inf where a wall contact holds a tangential spring (``Walls``): the rule by which
    ``_integrate_range`` skips the walls of a granule farther from all of them than it can have
    moved since x_ref plus the call's reach. The gap is 1-Lipschitz in the position and
    ``touching`` needs gap < ½ reach, so a skipped granule has no wall force and no spring; the
    gap is stored 1e-9 r_i short, room for its rounding against ``wall_force``'s."""
    for i in range(x_ref.shape[0]):
        g = math.inf
        for s in range(rows.shape[0]):
            if wall_hist[i, s] != 0.0:
                g = -math.inf
                break
            if rows[s, 0] == WALL_CHAMBER:
                dx = x_ref[i, 0] - rows[s, 1]
                dy = x_ref[i, 1] - rows[s, 2]
                g = min(g, rows[s, 3] - math.sqrt(dx * dx + dy * dy) - r[i])
            else:
                g = min(
                    g,
                    (x_ref[i, 0] - rows[s, 1]) * rows[s, 3]
                    + (x_ref[i, 1] - rows[s, 2]) * rows[s, 4]
                    - r[i],
                )
        gap[i] = g - 1e-9 * r[i]


@njit(cache=True, fastmath=FASTMATH)
def mark_special(wall_gap, covered, cstart, held, flags, order):
    """Flag the granules the per-granule pass must take on its full path (``_integrate_range``):
    those within covered (m) of a wall (wall_gap, ``wall_gaps``), with an entry in the polygon
    candidate list (cstart, ``Candidates.start``) or held by a bond. Writes flags (n,) int8 and
    their indices in increasing order to order (n,) int64; returns their count."""
    count = 0
    for i in range(flags.shape[0]):
        special = wall_gap[i] <= covered or cstart[i + 1] > cstart[i] or held[i] != 0
        flags[i] = special
        if special:
            order[count] = i
            count += 1
    return count


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _free_step(
    i, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, dt, damp, v_cap, gravity, keep, single
):  # fmt: skip
    """Granule i's step on the free path (``_integrate_free``); returns its |x − x_ref|²,
    |v|², |v + ½ dt a_prev|²."""
    fx, fy, t = add_pair_forces(acc, i, 0.0, 0.0, 0.0, single)
    if keep:
        f[i, 0] = fx
        f[i, 1] = fy
        tq[i] = t
    kick_drift_one(i, x, v, w, m, inertia, fx, fy, t, gravity, dt, damp, v_cap, a_prev)
    return motion_of(i, x, v, a_prev, x_ref, 0.5 * dt)


@njit(cache=True, parallel=True, fastmath=FASTMATH, error_model="numpy")
def _integrate_free(
    lo, hi, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, flags, free, dt, damp, v_cap,
    gravity, keep,
):  # fmt: skip
    """The free path of ``_integrate_range``: every granule i of lo:hi not flagged sums its pair
    forces (acc, whose rows it zeroes for the next pair pass; into f and tq if keep) and moves
    (``stepping.kick_drift_one``); returns their (max displacement², max speed², max
    extrapolated speed²) (``stepping.motion_of``). While granules coast, free lists the
    unflagged ones in increasing order (empty otherwise): the loop takes them from it instead
    of testing every granule's flag, a branch the coasting granules would make unpredictable.
    A function of its own, not inlined: the small loop compiles tighter than inside the full
    path's function (docs/dev/performance.md). Compiled as the passes are (parallel=True,
    error_model="numpy": the same arithmetic).

    One chunk of a step without drag (damp = 1) or speed cap (v_cap = ∞), as every step but
    ``relax``'s, runs a copy of the loop compiled with those constants, reading that chunk
    alone (``stepping.add_pair_forces``): the unused terms then cost nothing (the cap's square
    root and division were computed and discarded for every granule,
    docs/dev/performance.md). The compiler may round the same arithmetic differently in the
    two copies (a last bit, docs/dev/performance.md)."""
    if acc.shape[0] == 1 and damp == 1.0 and v_cap == math.inf:
        return _free_loop(
            lo, hi, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, flags, free, dt, 1.0,
            math.inf, gravity, keep, True,
        )  # fmt: skip
    return _free_loop(
        lo, hi, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, flags, free, dt, damp, v_cap,
        gravity, keep, False,
    )  # fmt: skip


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _free_loop(
    lo, hi, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, flags, free, dt, damp, v_cap,
    gravity, keep, single,
):  # fmt: skip
    """The loop of ``_integrate_free``; single: acc holds one chunk (``add_pair_forces``)."""
    dmax = 0.0
    smax = 0.0
    umax = 0.0
    if free.shape[0] == 0:
        for i in range(lo, hi):
            if flags[i]:
                continue
            d2, s2, u2 = _free_step(
                i, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, dt, damp, v_cap, gravity, keep,
                single,
            )  # fmt: skip
            dmax = max(dmax, d2)
            smax = max(smax, s2)
            umax = max(umax, u2)
        return dmax, smax, umax
    for a in range(np.searchsorted(free, lo), np.searchsorted(free, hi)):
        d2, s2, u2 = _free_step(
            free[a], x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, dt, damp, v_cap, gravity,
            keep, single,
        )  # fmt: skip
        dmax = max(dmax, d2)
        smax = max(smax, s2)
        umax = max(umax, u2)
    return dmax, smax, umax


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _stop(i, v, w, a_prev):
    """Granule i at rest, its last accelerations zero (held in its cell)."""
    v[i, 0] = 0.0
    v[i, 1] = 0.0
    w[i] = 0.0
    a_prev[i, 0] = 0.0
    a_prev[i, 1] = 0.0
    a_prev[i, 2] = 0.0


@njit(cache=True, inline="always", fastmath=FASTMATH)
def _integrate_range(
    lo, hi, x, v, w, a_prev, r, m, inertia, mat, params, rows, wall_hist, walls_near, acc, f, tq,
    bonds, poly, table, phist, rho, cstart, cpoly, ploads, x_ref, scalars,
):  # fmt: skip
    """The per-granule pass of ``_integrate`` for granules lo:hi, from arrays (the bundles'
    fields, cand's), walls_near = (wall_gap (``wall_gaps``), flags, order, free) and scalars = (dt,
    damp = 1/(1 + drag·dt), v_cap, step, reach, near, gravity, keep) (tuples: a call of more
    than 30 arguments compiles to one numba cannot inline): a granule's walls are evaluated only
    where wall_gap ≤ near; the total force and torque go to f and tq only if keep (the call's
    last step, whose forces alone are read after the call); returns the range's (max
    displacement², max speed², wall dissipation, max extrapolated speed², polygon contacts
    opened or closed, granules released) (``_integrate``).

    Two loops over disjoint granules: the flagged ones (``mark_special``: every granule that
    can reach a wall or a polygon or is held; order lists them) take the full path in index
    order, then every other granule only sums its pair forces and moves (``_integrate_free``).
    A granule's step reads and writes only its own state (and its candidate entries), so the
    split gives the same floats. ``bonds`` is unpacked first: written through a named tuple's
    fields inside ``_integrate``'s parallel loop, an array keeps none of the writes (numba
    0.68)."""
    dt, damp, v_cap, step, reach, near, gravity, keep = scalars
    wall_gap, flags, order, free = walls_near
    held, bond_force, bond_energy, released_step, release_force = bonds
    h = 0.5 * dt
    dmax = 0.0
    smax = 0.0
    umax = 0.0
    lost = 0.0
    changes = 0
    releases = 0
    for s in range(np.searchsorted(order, lo), np.searchsorted(order, hi)):
        i = order[s]
        fx = 0.0
        fy = 0.0
        t = 0.0
        if wall_gap[i] <= near:
            fx, fy, t, de = wall_force(
                i, x, v, w, a_prev, r, m, inertia, mat, params, rows, wall_hist, dt, reach
            )
            lost += de
        fx, fy, t = add_pair_forces(acc, i, fx, fy, t, acc.shape[0] == 1)
        for e in range(cstart[i], cstart[i + 1]):
            was = phist[i, cpoly[e], HIST_ACTIVE] != 0.0
            now, px, py, ti, tk, de = polygon_contact(
                i, cpoly[e], x, v, w, r, m, mat, poly, table, rho, dt, phist
            )
            changes += now != was
            fx += px
            fy += py
            t += ti
            ploads[e, 0] = -px
            ploads[e, 1] = -py
            ploads[e, 2] = tk
            ploads[e, 3] = de
        if keep:
            f[i, 0] = fx
            f[i, 1] = fy
            tq[i] = t
        if held[i] == 1:
            load = math.hypot(fx + m[i] * gravity[0], fy + m[i] * gravity[1])
            if load <= bond_force[i]:
                _stop(i, v, w, a_prev)
                continue
            release_force[i] = load
            weight = m[i] * math.hypot(gravity[0], gravity[1])
            if bond_energy[i] == math.inf or weight > bond_force[i]:
                held[i] = 0
                released_step[i] = step
                releases += 1
            else:
                held[i] = 2
        elif held[i] == 2 and fx == 0.0 and fy == 0.0 and t == 0.0:
            energy = 0.5 * (m[i] * (v[i, 0] ** 2 + v[i, 1] ** 2) + inertia[i] * w[i] ** 2)
            if energy <= bond_energy[i]:
                lost += energy
                held[i] = 1
                release_force[i] = math.nan
                _stop(i, v, w, a_prev)
                continue
            lost += bond_energy[i]
            share = math.sqrt(1.0 - bond_energy[i] / energy)
            v[i, 0] *= share
            v[i, 1] *= share
            w[i] *= share
            held[i] = 0
            released_step[i] = step
            releases += 1
        kick_drift_one(i, x, v, w, m, inertia, fx, fy, t, gravity, dt, damp, v_cap, a_prev)
        d2, s2, u2 = motion_of(i, x, v, a_prev, x_ref, h)
        dmax = max(dmax, d2)
        smax = max(smax, s2)
        umax = max(umax, u2)
    fmax = _integrate_free(
        lo, hi, x, v, w, a_prev, m, inertia, acc, f, tq, x_ref, flags, free, dt, damp, v_cap,
        gravity, keep,
    )  # fmt: skip
    dmax = max(dmax, fmax[0])
    smax = max(smax, fmax[1])
    umax = max(umax, fmax[2])
    return dmax, smax, lost, umax, changes, releases


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def _integrate(
    granules, props, bonds, params, walls, poly, table, phist, rho, cand, settings, work, x_ref,
    chunk, step, reach, walls_near, near,
):  # fmt: skip
    """Fused per-granule pass: wall and polygon forces, sum of chunks, kick-drift, displacement².

    Writes the step's total contact force and torque to work.f and work.tq at the call's last
    step (settings.first_step + settings.n_steps − 1); chunk[c] = (max
    displacement² since the list build (m²), max speed² (m²/s²), wall dissipation (J), max
    extrapolated speed² |v + ½ dt a_prev|² for the next step (m²/s²), polygon contacts opened
    or closed, granules released) of chunk c (per-chunk values instead of shared reduction
    variables). Polygon contacts: the candidate pairs ``cand`` (``Candidates``) of each granule
    with the posed polygons poly (``PolygonArrays``) of bounding radii rho (m), table
    (``TableArrays``) and history phist; entry e's load on its polygon and dissipation go to
    cand.loads[e] (``polygon_forces.add_loads``). ``bonds`` (``Bonds``) hold or release each
    granule (module doc); ``step`` is the step's number; reach, m: as in ``pair_force``;
    walls_near = (wall_gap, flags, order, free): the walls of granule i are evaluated only where
    wall_gap[i] ≤ near, m (``wall_gaps``), and only the granules flagged by ``mark_special``
    (listed in order) take the full path (``_integrate_range``). The
    polygon bundles come as arguments, not as a ``Polygons``: a parallel loop takes a named
    tuple only from an argument or a constructor call (numba 0.68); the other bundles are
    unpacked before the loop (module doc). One chunk runs in ``_integrate_serial`` (no parallel
    region to open).
    """
    x, v, w, a_prev = granules.x, granules.v, granules.w, granules.a_prev
    r, m, inertia, mat = props.r, props.m, props.inertia, props.mat
    rows, wall_hist = walls.rows, walls.hist
    acc, f, tq = work.acc, work.f, work.tq
    cstart, cpoly, ploads = cand.start, cand.polygon, cand.loads
    dt, gravity, v_cap = settings.dt, settings.gravity, settings.v_cap
    damp = 1.0 / (1.0 + settings.drag * dt)
    n = x.shape[0]
    n_chunks = acc.shape[0]
    for c in prange(n_chunks):
        dmax, smax, lost, umax, changes, releases = _integrate_range(
            c * n // n_chunks, (c + 1) * n // n_chunks, x, v, w, a_prev, r, m, inertia, mat,
            params, rows, wall_hist, walls_near, acc, f, tq, bonds, poly, table, phist, rho,
            cstart, cpoly, ploads, x_ref,
            (dt, damp, v_cap, step, reach, near, gravity,
             step == settings.first_step + settings.n_steps - 1),
        )  # fmt: skip
        chunk[c, 0] = dmax
        chunk[c, 1] = smax
        chunk[c, 2] = lost
        chunk[c, 3] = umax
        chunk[c, 4] = changes
        chunk[c, 5] = releases


@njit(cache=True, parallel=True, fastmath=FASTMATH, error_model="numpy")
def _integrate_serial(
    granules, props, bonds, params, walls, poly, table, phist, rho, cand, settings, work, x_ref,
    chunk, step, reach, walls_near, near,
):  # fmt: skip
    """``_integrate`` on one thread, chunk after chunk, without a parallel region."""
    x, v, w, a_prev = granules.x, granules.v, granules.w, granules.a_prev
    r, m, inertia, mat = props.r, props.m, props.inertia, props.mat
    damp = 1.0 / (1.0 + settings.drag * settings.dt)
    n = x.shape[0]
    n_chunks = work.acc.shape[0]
    for c in range(n_chunks):
        dmax, smax, lost, umax, changes, releases = _integrate_range(
            c * n // n_chunks, (c + 1) * n // n_chunks, x, v, w, a_prev, r, m, inertia, mat,
            params, walls.rows, walls.hist, walls_near, work.acc, work.f, work.tq, bonds, poly,
            table, phist, rho, cand.start,
            cand.polygon, cand.loads, x_ref,
            (settings.dt, damp, settings.v_cap, step, reach, near, settings.gravity,
             step == settings.first_step + settings.n_steps - 1),
        )  # fmt: skip
        chunk[c, 0] = dmax
        chunk[c, 1] = smax
        chunk[c, 2] = lost
        chunk[c, 3] = umax
        chunk[c, 4] = changes
        chunk[c, 5] = releases


@njit(cache=True)
def _motion(x, v, a_prev, x_ref, dt):
    """(max |x − x_ref|², m²; max |v|², m²/s²; max |v + ½ dt a_prev|², m²/s²) over the granules:
    the list's staleness and the pairs' reach (``pair_force``) at a call's start."""
    h = 0.5 * dt
    dmax = 0.0
    smax = 0.0
    umax = 0.0
    for i in range(x.shape[0]):
        d2, s2, u2 = motion_of(i, x, v, a_prev, x_ref, h)
        dmax = max(dmax, d2)
        smax = max(smax, s2)
        umax = max(umax, u2)
    return dmax, smax, umax


@njit(cache=True, nogil=True)
def advance(settings, granules, props, bonds, params, walls, polygons, nbrs, work, opening):
    """Advance settings.n_steps symplectic Euler steps on one thread; returns (start, nbr, hist,
    n_rebuilds, cand_start, cand_polygon, n_lists, coasted): the neighbour list after the call,
    the number of rebuilds, the polygon candidate list after the call (``CandidateList``'s start
    and polygon), the number of candidate lists built and the granule steps taken coasting
    (``perga.contact.soft.coasting``, where settings.coast).

    The bundles are those of the module doc; each may also be a plain tuple in its fields' order
    (``tuple(bundle)``, for ``Polygons`` its parts too): numba types a named-tuple argument by
    its class and field names on every call, which costs more than the kernel on small systems
    (docs/dev/performance.md), so ``SoftGranules.step`` passes plain tuples.

    Before its first step the call does what opening (``Opening``) asks: the floor kick, then
    the copy of the state. work.acc must hold zeros, as ``new_accumulator`` makes it: the pair
    pass adds into it and the per-granule pass zeroes each row after reading it (one pass over
    it fewer a step).
    settings.pairs False skips granule-granule contacts (no pair list built, no pair loop).

    Rebuilds the neighbour list (carrying the tangential history over) before a step when
    2·(largest displacement since the last build) + dt·(largest speed) exceeds the skin (the
    dt·v term keeps listed every pair that ``touching`` may need half a step before first
    contact), when nbrs.start is not a list for these n granules, or when settings.rebuild;
    nbrs.x_ref holds the positions at the last build and is updated in place. The polygon
    candidate list (``polygon_forces.candidates``) is built after every rebuild, and at the
    first step unless the list polygons.listed still holds (``candidates_hold``: built since
    the last rebuild with its reach lengthened by ``CANDIDATE_MARGIN`` skins, and the polygons
    have not moved through that margin); a list that holds any pair that can touch
    gives the same floats as the shortest one (a pair out of reach adds zeros). On return
    work.f and work.tq hold the contact forces and torques of the last step, granules.a_prev
    its accelerations, the polygons their pose n_steps·dt after the call's start and their
    loads the mean force, torque and moment over the call; work.dissipated and work.counts
    have been added to.
    """
    return _advance(
        settings, granules, props, bonds, params, walls, polygons, nbrs, work, opening,
        _pair_forces_serial, _integrate_serial,
    )  # fmt: skip


@njit(cache=True, nogil=True)
def advance_threaded(
    settings, granules, props, bonds, params, walls, polygons, nbrs, work, opening
):  # fmt: skip
    """``advance`` with the chunks of work.acc computed on numba's threads."""
    return _advance(
        settings, granules, props, bonds, params, walls, polygons, nbrs, work, opening,
        pair_forces, _integrate,
    )  # fmt: skip


@njit(inline="always")
def _advance(
    settings, granules, props, bonds, params, walls, polygons, nbrs, work, opening, pair_pass,
    integrate_pass,
):  # fmt: skip
    """The body of ``advance`` with its pair pass (``pair_forces`` or ``_pair_forces_serial``)
    and per-granule pass (``_integrate`` or ``_integrate_serial``); inlined into each entry, so
    that each compiles only the passes it calls."""
    settings = Settings(*settings)
    granules = Granules(*granules)
    props = GranuleProps(*props)
    bonds = Bonds(*bonds)
    walls = Walls(*walls)
    polygons = Polygons(*polygons)
    polygons = Polygons(
        PolygonArrays(*polygons.arrays),
        TableArrays(*polygons.table),
        polygons.hist,
        PolygonLoads(*polygons.loads),
        CandidateList(*polygons.listed),
    )
    nbrs = NeighbourList(*nbrs)
    work = Work(*work)
    _open(granules, props.m, polygons.arrays, Opening(*opening))
    x, v, r = granules.x, granules.v, props.r
    n_steps, dt, skin, pairs = settings.n_steps, settings.dt, settings.skin, settings.pairs
    start, nbr, hist, x_ref = nbrs.start, nbrs.nbr, nbrs.hist, nbrs.x_ref
    poly, phist, loads = polygons.arrays, polygons.hist, polygons.loads
    force, torque, moment = loads.force, loads.torque, loads.moment
    dissipated, counts = work.dissipated, work.counts
    n = x.shape[0]
    n_chunks = work.acc.shape[0]
    n_poly = force.shape[0]
    origin = Pose(poly.vertices.copy(), poly.com.copy(), poly.pivot.copy())
    since = np.zeros(n_poly)
    start_velocity, start_omega = poly.velocity.copy(), poly.omega.copy()
    step_loads = np.zeros((n_poly, 3))
    body_loads, kicks = np.zeros((n_poly, 3)), np.zeros((n_poly, 3))  # kick_bodies' work
    kicked = False
    rho = bounding_radii(poly.vertices, poly.start, poly.com)
    force[:, :] = 0.0
    torque[:] = 0.0
    moment[:] = 0.0
    loads.recoil[:, :] = 0.0
    chunk = np.zeros((n_chunks, 6))
    lost = np.zeros(n_chunks)
    cand = Candidates(np.zeros(n + 1, np.int64), np.zeros(0, np.int64), np.zeros((0, 4)))
    cstart, cpoly = polygons.listed.start, polygons.listed.polygon
    built, reach_built = polygons.listed.vertices, polygons.listed.reach
    needed = np.empty(n_poly)
    n_lists = 0
    n_rebuilds = 0
    dmax, smax, umax = _motion(x, v, granules.a_prev, x_ref, dt)
    tangential = np.any(params[:, :, P_MU] != 0.0) or np.any(params[:, :, P_DAMPT] != 0.0)
    rolling = np.any(params[:, :, P_MUR] != 0.0)
    linear = np.all(params[:, :, P_HERTZ] == LINEAR)
    wall_gap = np.empty(n)
    near = 0.0
    flags = np.empty(n, np.int8)
    order = np.empty(n, np.int64)
    n_special = 0
    covered = -math.inf
    need = settings.rebuild or (pairs and start.shape[0] != n + 1)
    need = need or 2.0 * math.sqrt(dmax) + dt * math.sqrt(smax) > skin
    fresh = False
    gravity = settings.gravity
    damp = 1.0 / (1.0 + settings.drag * dt)
    maxima = np.empty((n_steps, 3))
    coasting = (np.empty(0, np.int64), np.empty((5, 0)), np.empty((3, 0)))
    first_coast = 0
    free = np.empty(0, np.int64)
    speed = 0.0
    bound = np.empty(n)  # each granule's own speed bound while granules coast
    outran = False  # a granule that does not coast went faster than its bound in the last step
    coasted = 0
    for step in range(n_steps):
        reach = dt * math.sqrt(umax)
        decide = False  # which granules coast, for the steps left
        if coasting[0].shape[0] > 0 and (need or outran or math.sqrt(dmax) + reach > covered):
            rewind(granules, flags, coasting, (step - first_coast, dt, damp, settings.v_cap))
            coasted -= coasting[0].shape[0] * (n_steps - step)
            coasting = (coasting[0][:0], np.empty((5, 0)), np.empty((3, 0)))
            free = free[:0]
            decide = True
        rebuilt = need
        if need:
            if pairs:
                start, nbr, hist = build(x, r, skin, start, nbr, hist)
            x_ref[:, :] = x
            n_rebuilds += 1
            fresh = False
            dmax = 0.0
        if need or step == 0:
            wall_gaps(x_ref, r, walls.rows, walls.hist, wall_gap)
            near = 0.0
        near = max(near, math.sqrt(dmax) + reach)
        if n_poly > 0:
            if step > 0:
                pose(origin, poly, step * dt, since)
            if not fresh:
                candidate_reach(poly, rho, (n_steps - 1 - step) * dt, skin, dt, needed)
                if (
                    rebuilt
                    or cstart.shape[0] != n + 1
                    or not candidates_hold(poly.vertices, poly.start, built, reach_built, needed)
                ):
                    for k in range(n_poly):
                        reach_built[k] = needed[k] + CANDIDATE_MARGIN * skin
                    built[:, :] = poly.vertices
                    cstart, cpoly = candidates(x_ref, r, poly, rho, phist, reach_built)
                    n_lists += 1
                cand = Candidates(cstart, cpoly, np.zeros((cpoly.shape[0], 4)))
                fresh = True
        if rebuilt or step == 0 or near > covered:  # wall gaps or candidates new, near grown
            covered = near + SPECIAL_MARGIN * skin
            n_special = mark_special(wall_gap, covered, cand.start, bonds.held, flags, order)
            decide = True
        if settings.coast and decide and coasting[0].shape[0] == 0 and n_steps - step > 1:
            speed = speed_bound(smax, umax, gravity, n_steps - step, dt)
            coasting, free = coast(
                granules, props, work.acc, work.f, work.tq, x_ref,
                (start, nbr, hist) if pairs else (start[:0], nbr, hist), flags,
                (n_steps - step, dt, gravity, damp, settings.v_cap, speed), maxima, bound,
            )  # fmt: skip
            first_coast = step
            coasted += coasting[0].shape[0] * (n_steps - step)
            free = free if coasting[0].shape[0] > 0 else free[:0]
        if pairs:
            pair_pass(
                x, v, granules.w, granules.a_prev, r, props.m, props.inertia, props.mat, params,
                start, nbr, hist, dt, reach, tangential, rolling, linear, work.acc, lost, flags,
            )  # fmt: skip
        integrate_pass(
            granules, props, bonds, params, walls, poly, polygons.table, phist, rho, cand,
            settings, work, x_ref, chunk, settings.first_step + step, reach,
            (wall_gap, flags, order[:n_special], free), near,
        )  # fmt: skip
        if n_poly > 0:
            dissipated[DISSIPATED_POLYGONS] += add_loads(cand, poly.com, loads, step_loads)
            if kick_bodies(poly, step_loads, dt, origin, since, step * dt, body_loads, kicks):
                kicked = True
                fresh = False  # the candidates' reach was for the old velocities
            if kicked and step < n_steps - 1:  # the last drift is the machine's next pose's
                add_recoil(poly, start_velocity, start_omega, dt, loads.recoil)
        dmax = 0.0
        smax = 0.0
        umax = 0.0
        for c in range(n_chunks):
            dmax = max(dmax, chunk[c, 0])
            smax = max(smax, chunk[c, 1])
            umax = max(umax, chunk[c, 3])
            dissipated[DISSIPATED_PAIRS] += lost[c]
            dissipated[DISSIPATED_WALLS] += chunk[c, 2]
            counts[COUNT_CONTACT_CHANGES] += int(chunk[c, 4])
            counts[COUNT_RELEASES] += int(chunk[c, 5])
        outran = coasting[0].shape[0] > 0 and (
            max(smax, umax) > speed * speed or outruns(v, granules.a_prev, free, bound, 0.5 * dt)
        )
        if coasting[0].shape[0] > 0:
            dmax = max(dmax, maxima[step - first_coast, 0])
            smax = max(smax, maxima[step - first_coast, 1])
            umax = max(umax, maxima[step - first_coast, 2])
        need = 2.0 * math.sqrt(dmax) + dt * math.sqrt(smax) > skin
    if n_poly > 0 and n_steps > 0:
        pose(origin, poly, n_steps * dt, since)
        if kicked:  # the velocities are the call's inputs
            poly.velocity[:, :] = start_velocity
            poly.omega[:] = start_omega
        force /= n_steps
        torque /= n_steps
        moment /= n_steps
    return start, nbr, hist, n_rebuilds, cstart, cpoly, n_lists, coasted


@njit(cache=True)
def _open(granules, m, poly, opening):
    """Opening's work (``Opening``) on granules (``Granules``) of masses m (n,), kg, and the
    polygons poly (``PolygonArrays``)."""
    if opening.energy.shape[0] == 2:
        where = granules.x if opening.corotating else granules.v
        floor_kick(granules.v, where, m, opening.dv_max, opening.omega, opening.energy)
    if opening.keep:
        x, v, w, vertices, com = opening.kept
        _copy(granules.x, x)
        _copy(granules.v, v)
        _copy(granules.w, w)
        _copy(poly.vertices, vertices)
        _copy(poly.com, com)


@njit(cache=True, inline="always")
def _copy(source, target):
    """Copy the C-contiguous array ``source`` into ``target`` of its shape, as one flat loop
    (numba's ``target[:] = source`` of a 2-D array indexes every element: slower,
    docs/dev/performance.md)."""
    a = source.reshape(-1)
    b = target.reshape(-1)
    for k in range(a.size):
        b[k] = a[k]


def new_accumulator(n_chunks: int, n: int) -> np.ndarray:
    """Per-chunk force accumulator (n_chunks, n, 3) for ``pair_forces`` and ``advance``."""
    return np.zeros((max(int(n_chunks), 1), n, 3))
