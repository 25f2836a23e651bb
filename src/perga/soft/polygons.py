"""Soft contacts between granules (discs) and convex polygons (hammers, rotor parts), SI units.

The polygons are rigid bodies posed by Pymunk at each step; this module only computes the contact
forces. Per polygon the caller gives its world-frame vertices (counter-clockwise), its body's centre
of mass c, linear velocity v_c and angular velocity ω (surface velocity v_c + ω × (p − c) at a
point p), and how it resists a contact impulse:

* ``FREE``: a free body of mass M and moment I_c about c: 1/m_p = 1/M + ((p − c) × n)²/I_c;
* ``PINNED``: hinged at a pivot A on a body of infinite inertia (the hammer on a kinematic rotor),
  moment I_A about A: 1/m_p = ((p − A) × n)²/I_A;
* ``KINEMATIC``: infinite inertia, 1/m_p = 0 (a wall, a rotor driven at constant ω).

Contact geometry: the closest feature of the polygon (an edge or a corner) to the disc centre.
A centre outside the polygon gets the normal from the closest boundary point (along centre-corner
at a corner); a centre inside gets the outward normal of the edge of deepest penetration (the
largest signed distance), overlap δ = r − s. The force acts at the middle of the overlap,
p = x − (r − δ⁺/2) n (the disc's surface point while δ ≤ 0), with the contact's effective mass
m_eff = 1/(1/m_i + 1/m_p).

Contact law: ``perga.soft.contacts.contact_force``, the same law (and the same time
discretisation) as granule pairs and walls, always clamped at zero (``end="force"``):

* ``LINEAR``: F_n = max(0, k_n δ + 2ζ√(k_n m_eff) δ̇), ζ = ``damping_ratio(e, "force")``;
* ``HERTZ``: F_n = max(0, k δ^{3/2} + α√(m_eff k) δ^{1/4} δ̇), k = k_n √r_i (k_n = (4/3) E*,
  Pa, with R_eff = r_i for a flat face), α = ``tsuji_alpha(e, "force")``.

A contact is evaluated whenever ``contacts.touching`` (δ > 0 somewhere in the kick interval
[t − dt/2, t + dt/2], so possibly half a step before first touch), and the dashpot enters as its
exact impulse over the overlapping part of that interval (see ``contact_force``). The approach
rate handed to the law is extrapolated to the force time: the caller's velocities are half a
step old (kick, then drift), and this module does not know the accelerations of the granules or
of the polygons (the granule kernel extrapolates u = v + ½ dt a_prev), so it extrapolates δ̇
from the last two half-step rates instead, 1.5 δ̇_{n−1/2} − 0.5 δ̇_{n−3/2} (δ̇_{n−1/2} unchanged
at the first evaluation of a contact, before any contact force acted; exact for a contact at
rest). For a normal approach this equals δ̇ + ½ dt δ̈ of the previous step, i.e. the kernel's
extrapolation. The tangential slip rate is not extrapolated.

Tangential force: Cundall-Strack spring F_t = −k_t ξ on the accumulated tangential displacement ξ
(a scalar per (granule, polygon) pair in 2-D, along t = (−n_y, n_x)), capped at f·F_n (ξ is
rescaled so that k_t|ξ| = f F_n while sliding); k_t constant (also for ``HERTZ``), no tangential
damping. History per (granule, polygon) pair, an array (n, n_poly, 3) owned by the caller (start
from zeros): [ξ (m), 1.0 if the contact was evaluated at the last call else 0.0, δ̇ of the last
call (m/s, not extrapolated)]; all three are reset to zero whenever the pair is not touching.
The caller must permute its rows with the granules if it reorders them.

Forces and torques on the granules are accumulated into the caller's ``f`` (n, 2) and ``tq`` (n,);
the equal and opposite force and its torque about each polygon's centre of mass are accumulated
into ``PolygonSet.force`` (n_poly, 2) and ``PolygonSet.torque`` (n_poly,), to be applied to the
Pymunk bodies. Both sides use the same force at the same point, so linear and angular momentum
are conserved to round-off.

Broad phase: a granule is skipped for a polygon when its centre is farther than r_i plus half a
step's largest possible approach from the polygon's bounding circle (centre at the vertex mean).
Granules are processed in a fixed number of chunks in parallel (numba ``prange``); per-polygon
sums are reduced chunk by chunk in a fixed order, so the result does not depend on the number of
threads.

Limits: a disc whose centre crosses the middle of a thin polygon in one step is pushed out of the
other side (tunnelling: see ``perga.analytic.contact.tunnelling_time_step``); rolling resistance is
not modelled; k_t is constant (no Mindlin δ^{1/2} scaling for ``HERTZ``, unlike the table rows
of ``contact_law``).
"""

import math
from dataclasses import dataclass, field

import numba as nb
import numpy as np

from perga.analytic.contact import damping_ratio, tsuji_alpha
from perga.soft.contacts import contact_force, touching

FREE = 0
"""Polygon kind: free rigid body (mass M and moment I_c about its centre of mass)."""
PINNED = 1
"""Polygon kind: body hinged at a pivot on an infinitely heavy carrier (moment I_A about it)."""
KINEMATIC = 2
"""Polygon kind: infinite inertia (walls, a rotor at imposed ω)."""

LINEAR = 0
"""Normal law: linear spring-dashpot F = k_n δ + c δ̇, clamped at zero."""
HERTZ = 1
"""Normal law: Hertz with Tsuji damping F = k δ^{3/2} + α√(m k) δ^{1/4} δ̇, clamped at zero."""

N_CHUNKS = 64
"""Granules are split into this many chunks for the parallel loop (fixed: deterministic sums)."""

_LAWS = {"linear": LINEAR, "hertz": HERTZ}


@dataclass
class PolygonSet:
    """Convex polygons, their motion, inertia and the loads the granules put on them (SI).

    Arrays (float64 unless stated, C-contiguous):
    vertices (n_vertices, 2): world-frame vertices of all polygons, each counter-clockwise,
    concatenated; start (n_poly + 1,) int64: polygon k owns vertices[start[k]:start[k + 1]];
    com (n_poly, 2): centre of mass, m; velocity (n_poly, 2): velocity of the centre of mass, m/s;
    omega (n_poly,): angular velocity, rad/s; kind (n_poly,) int32: FREE, PINNED or KINEMATIC;
    mass (n_poly,): M, kg (FREE only); inertia (n_poly,): I_c about com (FREE) or I_A about the
    pivot (PINNED), kg·m²; pivot (n_poly, 2): hinge position A, m (PINNED only);
    mat (n_poly,) int32: material index (column of the ``ContactTable``).
    force (n_poly, 2), N, and torque (n_poly,), N·m about com: loads accumulated by
    ``polygon_contacts``; zero them with ``clear_loads`` before each force evaluation.

    Update the pose in place each step (``set_pose``), e.g. from Pymunk's
    ``body.local_to_world`` of the shape's local vertices, ``body.position`` (plus the rotated
    ``center_of_gravity``), ``body.velocity`` and ``body.angular_velocity``.
    """

    vertices: np.ndarray
    start: np.ndarray
    com: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    kind: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    pivot: np.ndarray
    mat: np.ndarray
    force: np.ndarray = field(init=False)
    torque: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        n_poly = self.com.shape[0]
        self.force = np.zeros((n_poly, 2))
        self.torque = np.zeros(n_poly)

    @property
    def n_poly(self) -> int:
        """Number of polygons."""
        return int(self.com.shape[0])

    def clear_loads(self) -> None:
        """Zero the accumulated polygon forces and torques."""
        self.force[:] = 0.0
        self.torque[:] = 0.0

    def set_pose(
        self,
        k: int,
        vertices: np.ndarray,
        com: np.ndarray | tuple[float, float],
        velocity: np.ndarray | tuple[float, float],
        omega: float,
    ) -> None:
        """Set polygon k's world vertices (same count and order), centre of mass and velocities."""
        lo, hi = int(self.start[k]), int(self.start[k + 1])
        self.vertices[lo:hi] = vertices
        self.com[k] = com
        self.velocity[k] = velocity
        self.omega[k] = omega


def _signed_area(vertices: np.ndarray) -> float:
    x, y = vertices[:, 0], vertices[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def polygon_set(
    vertices: list[np.ndarray],
    com: np.ndarray,
    *,
    kind: list[int] | np.ndarray,
    mass: list[float] | np.ndarray | None = None,
    inertia: list[float] | np.ndarray | None = None,
    pivot: np.ndarray | None = None,
    velocity: np.ndarray | None = None,
    omega: np.ndarray | None = None,
    mat: list[int] | np.ndarray | None = None,
) -> PolygonSet:
    """Build a ``PolygonSet`` from a list of (m_k, 2) world-vertex arrays and per-polygon data.

    Checks that each polygon has at least 3 vertices, is counter-clockwise and convex, and that
    FREE polygons have M > 0 and I_c > 0 and PINNED ones I_A > 0 (``math.inf`` is allowed and makes
    the body kinematic for the contact). Missing velocities default to zero, materials to 0.
    """
    n_poly = len(vertices)
    polys = [np.ascontiguousarray(p, dtype=np.float64) for p in vertices]
    for k, p in enumerate(polys):
        if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 3:
            raise ValueError(f"polygon {k}: vertices must be (m >= 3, 2) (got {p.shape})")
        if not _signed_area(p) > 0.0:
            raise ValueError(f"polygon {k}: vertices must be counter-clockwise, non-degenerate")
        edges = np.roll(p, -1, axis=0) - p
        turn = edges[:, 0] * np.roll(edges[:, 1], -1) - edges[:, 1] * np.roll(edges[:, 0], -1)
        if np.any(turn < 0.0):
            raise ValueError(f"polygon {k}: must be convex (decompose concave outlines)")
    start = np.zeros(n_poly + 1, dtype=np.int64)
    start[1:] = np.cumsum([p.shape[0] for p in polys])

    def per_poly(values, default: float, dtype=np.float64, width: int | None = None):
        shape = (n_poly,) if width is None else (n_poly, width)
        if values is None:
            return np.full(shape, default, dtype=dtype)
        out = np.ascontiguousarray(values, dtype=dtype)
        if out.shape != shape:
            raise ValueError(f"per-polygon array must have shape {shape} (got {out.shape})")
        return out.copy()

    kinds = per_poly(kind, KINEMATIC, np.int32)
    masses = per_poly(mass, math.inf)
    inertias = per_poly(inertia, math.inf)
    for k in range(n_poly):
        if kinds[k] == FREE and not (masses[k] > 0.0 and inertias[k] > 0.0):
            raise ValueError(f"polygon {k}: FREE needs mass > 0 and inertia > 0")
        if kinds[k] == PINNED and not inertias[k] > 0.0:
            raise ValueError(f"polygon {k}: PINNED needs inertia (about the pivot) > 0")
        if kinds[k] not in (FREE, PINNED, KINEMATIC):
            raise ValueError(f"polygon {k}: unknown kind {kinds[k]}")
    return PolygonSet(
        vertices=np.ascontiguousarray(np.concatenate(polys, axis=0)),
        start=start,
        com=per_poly(com, 0.0, width=2),
        velocity=per_poly(velocity, 0.0, width=2),
        omega=per_poly(omega, 0.0),
        kind=kinds,
        mass=masses,
        inertia=inertias,
        pivot=per_poly(pivot, 0.0, width=2),
        mat=per_poly(mat, 0, np.int32),
    )


@dataclass(frozen=True)
class ContactTable:
    """Granule-polygon contact parameters per (granule material, polygon material), SI.

    Arrays (n_granule_mat, n_polygon_mat): law (int32, LINEAR or HERTZ); k_n (N/m for LINEAR;
    (4/3)E* in Pa for HERTZ, the stiffness being k_n √r_i in N/m^{3/2}); k_t (N/m); damping (ζ for
    LINEAR, Tsuji α for HERTZ, both for the force-clamped end criterion); friction f.
    """

    law: np.ndarray
    k_n: np.ndarray
    k_t: np.ndarray
    damping: np.ndarray
    friction: np.ndarray


def contact_table(
    k_n: float | np.ndarray,
    k_t: float | np.ndarray,
    e: float | np.ndarray,
    friction: float | np.ndarray,
    law: str = "linear",
) -> ContactTable:
    """Contact table from k_n, k_t, restitution e and friction f (scalars or (n_gm, n_pm) arrays).

    The damping is tuned with the force-clamped end criterion: ζ = damping_ratio(e, "force") for
    ``law="linear"``, α = tsuji_alpha(e, "force") for ``law="hertz"``; e in (e^-2, 1].
    """
    if law not in _LAWS:
        raise ValueError(f"law must be 'linear' or 'hertz' (got {law!r})")
    arrays = np.broadcast_arrays(
        *(np.atleast_2d(np.asarray(a, dtype=np.float64)) for a in (k_n, k_t, e, friction))
    )
    kn, kt, ee, ff = (np.ascontiguousarray(a) for a in arrays)
    if np.any(kn <= 0.0) or np.any(kt < 0.0) or np.any(ff < 0.0):
        raise ValueError("need k_n > 0, k_t >= 0, friction >= 0")
    tune = damping_ratio if law == "linear" else tsuji_alpha
    damping = np.vectorize(lambda x: tune(float(x), "force"), otypes=[np.float64])(ee)
    return ContactTable(
        law=np.full(kn.shape, _LAWS[law], dtype=np.int32),
        k_n=kn,
        k_t=kt,
        damping=np.ascontiguousarray(damping),
        friction=ff,
    )


@nb.njit(cache=True, inline="always")
def _closest_feature(px, py, verts, lo, hi):
    """Signed distance d of (px, py) to the polygon boundary (< 0 inside) and the normal n.

    Outside: d = distance to the closest boundary point, n from that point to the centre.
    Inside: d = largest edge signed distance (≤ 0), n = that edge's outward normal.
    """
    m = hi - lo
    s_max = -np.inf
    nx_max = 0.0
    ny_max = 0.0
    for j in range(m):
        ax, ay = verts[lo + j, 0], verts[lo + j, 1]
        jb = lo + j + 1 if j + 1 < m else lo
        ex = verts[jb, 0] - ax
        ey = verts[jb, 1] - ay
        inv = 1.0 / math.sqrt(ex * ex + ey * ey)
        nx = ey * inv
        ny = -ex * inv
        s = (px - ax) * nx + (py - ay) * ny
        if s > s_max:
            s_max = s
            nx_max = nx
            ny_max = ny
    if s_max <= 0.0:
        return s_max, nx_max, ny_max
    # Outside: closest point over all edges (segments).
    d2_min = np.inf
    qx_min = 0.0
    qy_min = 0.0
    for j in range(m):
        ax, ay = verts[lo + j, 0], verts[lo + j, 1]
        jb = lo + j + 1 if j + 1 < m else lo
        ex = verts[jb, 0] - ax
        ey = verts[jb, 1] - ay
        t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
        t = min(max(t, 0.0), 1.0)
        qx = ax + t * ex
        qy = ay + t * ey
        d2 = (px - qx) * (px - qx) + (py - qy) * (py - qy)
        if d2 < d2_min:
            d2_min = d2
            qx_min = qx
            qy_min = qy
    d = math.sqrt(d2_min)
    return d, (px - qx_min) / d, (py - qy_min) / d


@nb.njit(cache=True, parallel=True)
def _polygon_contacts(
    x, v, w, r, m, mat,
    verts, start, com, pvel, pomega, kind, pmass, pinertia, pivot, pmat,
    law, k_n, k_t, damping, friction,
    dt, hist, f, tq, pforce, ptorque,
):  # fmt: skip
    n = x.shape[0]
    n_poly = com.shape[0]
    # Bounding circles: centre at the vertex mean, radius to the farthest vertex.
    bound = np.empty((n_poly, 3))
    off = np.empty(n_poly)  # |centre of mass - bounding centre|
    pspeed = np.empty(n_poly)
    for k in range(n_poly):
        lo, hi = start[k], start[k + 1]
        bx = 0.0
        by = 0.0
        for j in range(lo, hi):
            bx += verts[j, 0]
            by += verts[j, 1]
        bx /= hi - lo
        by /= hi - lo
        rr = 0.0
        for j in range(lo, hi):
            rr = max(rr, (verts[j, 0] - bx) ** 2 + (verts[j, 1] - by) ** 2)
        bound[k, 0] = bx
        bound[k, 1] = by
        bound[k, 2] = math.sqrt(rr)
        off[k] = math.sqrt((com[k, 0] - bx) ** 2 + (com[k, 1] - by) ** 2)
        pspeed[k] = math.sqrt(pvel[k, 0] ** 2 + pvel[k, 1] ** 2)
    speed = np.empty(n)
    for i in range(n):
        speed[i] = math.sqrt(v[i, 0] ** 2 + v[i, 1] ** 2)
    n_chunks = min(N_CHUNKS, max(n, 1))
    part = np.zeros((n_chunks, n_poly, 3))
    counts = np.zeros(n_chunks, dtype=np.int64)
    for c in nb.prange(n_chunks):
        i_lo = c * n // n_chunks
        i_hi = (c + 1) * n // n_chunks
        for i in range(i_lo, i_hi):
            xi = x[i, 0]
            yi = x[i, 1]
            ri = r[i]
            for k in range(n_poly):
                dx = xi - bound[k, 0]
                dy = yi - bound[k, 1]
                reach = bound[k, 2] + ri
                d2 = dx * dx + dy * dy
                # Skip when even the fastest approach cannot make it touch within the step:
                # |rate| <= 1.5 |v_i - v_p| + 0.5 |last rate|, |v_p| <= |v_c| + |w| |p - c|.
                if d2 >= reach * reach and not (
                    math.sqrt(d2) - reach < 0.5 * dt * (1.5 * (
                        speed[i] + pspeed[k] + abs(pomega[k]) * (math.sqrt(d2) + ri + off[k])
                    ) + 0.5 * abs(hist[i, k, 2]))
                ):  # fmt: skip
                    if hist[i, k, 1] != 0.0:  # forget a contact that has ended
                        hist[i, k, 0] = 0.0
                        hist[i, k, 1] = 0.0
                        hist[i, k, 2] = 0.0
                    continue
                d, nx, ny = _closest_feature(xi, yi, verts, start[k], start[k + 1])
                delta = ri - d
                # Contact point: middle of the overlap (the surface point before first touch);
                # tangent t = (-ny, nx).
                arm = ri - 0.5 * max(delta, 0.0)
                px = xi - arm * nx
                py = yi - arm * ny
                tx = -ny
                ty = nx
                # Relative velocity of the disc's material point to the polygon's at p.
                rcx = px - com[k, 0]
                rcy = py - com[k, 1]
                vdx = v[i, 0] + w[i] * arm * ny
                vdy = v[i, 1] - w[i] * arm * nx
                vpx = pvel[k, 0] - pomega[k] * rcy
                vpy = pvel[k, 1] + pomega[k] * rcx
                vrx = vdx - vpx
                vry = vdy - vpy
                delta_dot = -(vrx * nx + vry * ny)
                vt = vrx * tx + vry * ty
                # delta_dot is the rate of the last half step; extrapolate it to the force time
                # from the previous one (no previous one at first touch: no contact force yet).
                rate = delta_dot
                if hist[i, k, 1] != 0.0:
                    rate = 1.5 * delta_dot - 0.5 * hist[i, k, 2]
                if not touching(delta, rate, dt):
                    if hist[i, k, 1] != 0.0:  # forget a contact that has ended
                        hist[i, k, 0] = 0.0
                        hist[i, k, 1] = 0.0
                        hist[i, k, 2] = 0.0
                    continue
                counts[c] += 1
                # Effective mass of this contact.
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
                else:
                    kn = k_n[a, b] * math.sqrt(ri)
                    damp = damping[a, b]
                    hertz = 1.0
                fn, ft, xi_t = contact_force(
                    kn, damp, hertz, 1.0, k_t[a, b], 0.0, friction[a, b],
                    delta, rate, vt, m_eff, hist[i, k, 0], dt,
                )  # fmt: skip
                hist[i, k, 0] = xi_t
                hist[i, k, 1] = 1.0
                hist[i, k, 2] = delta_dot
                fx = fn * nx + ft * tx
                fy = fn * ny + ft * ty
                f[i, 0] += fx
                f[i, 1] += fy
                tq[i] += -arm * ft
                part[c, k, 0] -= fx
                part[c, k, 1] -= fy
                part[c, k, 2] -= rcx * fy - rcy * fx
    total = 0
    for c in range(n_chunks):
        total += counts[c]
        for k in range(n_poly):
            pforce[k, 0] += part[c, k, 0]
            pforce[k, 1] += part[c, k, 1]
            ptorque[k] += part[c, k, 2]
    return total


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
    """Accumulate granule-polygon contact forces; return the number of contacts evaluated.

    A contact counts while ``touching`` (module doc): from up to half a step before first touch
    to the step after the force has returned to zero.

    Granules: x, v (n, 2), w, r, m (n,), mat (n,) int32 (row of ``table``). dt: time step, s
    (advances the tangential springs). history (n, n_poly, 3): contact history (module doc),
    updated in place (start from zeros). Adds to f (n, 2), tq (n,) and to ``polygons.force``,
    ``polygons.torque`` (about each centre of mass). Layouts are checked here; the compiled
    kernel ``_polygon_contacts`` takes the same arrays without checks.
    """
    n = x.shape[0]
    n_poly = polygons.n_poly
    expected = {
        "x": (x, (n, 2), np.float64),
        "v": (v, (n, 2), np.float64),
        "w": (w, (n,), np.float64),
        "r": (r, (n,), np.float64),
        "m": (m, (n,), np.float64),
        "mat": (mat, (n,), np.int32),
        "history": (history, (n, n_poly, 3), np.float64),
        "f": (f, (n, 2), np.float64),
        "tq": (tq, (n,), np.float64),
    }
    for name, (arr, shape, dtype) in expected.items():
        if arr.shape != shape or arr.dtype != dtype or not arr.flags.c_contiguous:
            raise ValueError(
                f"{name} must be C-contiguous {np.dtype(dtype).name} of shape {shape} "
                f"(got {arr.dtype.name} {arr.shape})"
            )
    n_gm, n_pm = table.k_n.shape
    if n and (mat.min() < 0 or mat.max() >= n_gm):
        raise ValueError(f"granule materials must be in [0, {n_gm})")
    if n_poly and (polygons.mat.min() < 0 or polygons.mat.max() >= n_pm):
        raise ValueError(f"polygon materials must be in [0, {n_pm})")
    if n == 0 or n_poly == 0:
        return 0
    p = polygons
    count = _polygon_contacts(
        x, v, w, r, m, mat,
        p.vertices, p.start, p.com, p.velocity, p.omega, p.kind, p.mass, p.inertia, p.pivot,
        p.mat,
        table.law, table.k_n, table.k_t, table.damping, table.friction,
        float(dt), history, f, tq, p.force, p.torque,
    )  # fmt: skip
    return int(count)
