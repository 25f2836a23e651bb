"""Soft contacts between granules (discs) and convex polygons (hammers, rotor parts), SI units.

The polygons are rigid bodies moved by the caller (Pymunk); this module computes the contact
forces. Per polygon the caller gives its world-frame vertices (counter-clockwise), its body's centre
of mass c, linear velocity v_c and angular velocity ω (surface velocity v_c + ω × (p − c) at a
point p), and how it resists a contact impulse:

* ``FREE``: a free body of mass M and moment I_c about c: 1/m_p = 1/M + ((p − c) × n)²/I_c;
* ``PINNED``: hinged at a pivot A on a body of infinite inertia (the hammer on a kinematic rotor),
  moment I_A about A: 1/m_p = ((p − A) × n)²/I_A;
* ``KINEMATIC``: infinite inertia, 1/m_p = 0 (a wall, a rotor driven at constant ω).

Two ways in: ``polygon_contacts`` evaluates all contacts once at the given poses (one force
evaluation, loads added to ``PolygonSet.force``/``torque``/``moment``); ``SoftGranules`` with
polygons evaluates them inside its compiled step (``kernel.advance``), moving each polygon
rigidly with its velocities during a call (``pose``) and returning the mean loads. Both call
``polygon_contact``, the one implementation of a granule-polygon contact.

Contact geometry: the closest feature of the polygon (an edge or a corner) to the disc centre.
A centre outside the polygon gets the normal from the closest boundary point (along centre-corner
at a corner); a centre inside gets the outward normal of the edge of deepest penetration (the
largest signed distance), overlap δ = r − s. The force acts at the middle of the overlap,
p = x − (r − δ⁺/2) n (the disc's surface point while δ ≤ 0), with the contact's effective mass
m_eff = 1/(1/m_i + 1/m_p).

Bodies of several convex pieces (a concave hammer, a chamber wall of segments): each piece is
a polygon, and only the body's outline makes contacts. Edges inside the body (seams between
pieces) are not solid; a corner contact counts only on the piece that owns a convex corner of
the outline, and only while the disc centre lies in that corner's region of the outline (between
the normals of the outline's two edges there). So a disc touching one face or corner of the
outline gets one contact whichever pieces it overlaps, and a disc in a concave notch gets one
per face it touches (``piece_features``; ``PolygonSet.solid`` and ``corner``). Where two faces
meet at a shallow concave joint (turning by less than ``SMOOTH_TURN``, e.g. the 2° joints of a
drawn round chamber) a disc near the joint overlaps both by nearly the same depth although it
presses on what is nearly one flat face: each face's contact then counts only on its side of
the joint's bisector, so the disc gets one contact (two would double the force: a granule with
e = 0.7 fired straight at a 2° joint left at 0.612).

Contact law: ``perga.contact.soft.laws.contact_force``, the same law (and the same time
discretisation and dissipation) as granule pairs and walls, clamped at zero (``end="force"``,
the default of ``contact_table``) or not (``end="overlap"``: max(0, ·) below is dropped and the
damping tuned for it):

* ``LINEAR``: F_n = max(0, k_n δ + 2ζ√(k_n m_eff) δ̇), ζ = ``damping_ratio(e, end)``;
  tangential stiffness k_t;
* ``HERTZ``: F_n = max(0, k δ^{3/2} + α√(m_eff k) δ^{1/4} δ̇), k = k_n √r_i (k_n = (4/3) E*,
  Pa, with R_eff = r_i for a flat face), α = ``tsuji_alpha(e, end)``; tangential stiffness
  k_t √(r_i δ) (Mindlin-like, as the k_t = P_KT √δ of the granule table's Hertz rows).

A contact is evaluated whenever ``contacts.touching`` (δ > 0 somewhere in the kick interval
[t − dt/2, t + dt/2], so possibly half a step before first touch), and the dashpot enters as its
exact impulse over the overlapping part of that interval (see ``contact_force``). The approach
and slip rates handed to the law are extrapolated to the force time: the caller's velocities are
half a step old (kick, then drift), and a polygon's acceleration is not known here, so each rate
u is extrapolated from its last two half-step values, 1.5 u_{n−1/2} − 0.5 u_{n−3/2} (u_{n−1/2}
unchanged at the first evaluation of a contact, before any contact force acted; exact for a
contact at rest). This equals u + ½ dt u̇ of the previous step, i.e. the granule kernel's
extrapolation; with stale rates e would be biased and the tangential spring's energy balance
only first order in dt.

Tangential force: Cundall-Strack spring F_t = −k_t ξ on the accumulated tangential displacement ξ
(a scalar per (granule, polygon) pair in 2-D, along t = (−n_y, n_x)), capped at f·F_n (ξ is
rescaled so that k_t|ξ| = f F_n while sliding), no tangential damping.

History per (granule, polygon) pair: an array (n, n_poly, HIST_COLUMNS) owned by the caller
(start from zeros; permute its rows with the granules if they are reordered), columns:

* ``HIST_XI``: ξ, m;
* ``HIST_ACTIVE``: 1.0 while the contact is evaluated (``touching``), else 0.0;
* ``HIST_RATE``: δ̇ of the last evaluation, m/s (not extrapolated);
* ``HIST_NORMAL_IMPULSE``: Σ F_n dt on the granule since the contact began, N·s (≥ 0);
* ``HIST_TANGENTIAL_IMPULSE``: Σ F_t dt on the granule along each step's tangent, N·s;
* ``HIST_DISSIPATED``: energy the contact dissipated since it began, J (``contact_force``; a
  tangential spring dropped at the end counts too);
* ``HIST_SLIP``: slip rate v_t of the last evaluation, m/s (not extrapolated).

When a contact ends ``HIST_XI``, ``HIST_ACTIVE``, ``HIST_RATE`` and ``HIST_SLIP`` are reset to 0;
the three totals are kept until the same pair's next contact begins (they are zeroed at its
first evaluation), so a caller comparing ``HIST_ACTIVE`` before and after a call reads the totals
of the contacts that ended.

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
other side (tunnelling: see ``perga.analytic.contact.tunnelling_time_step``); rolling resistance is
not modelled.
"""

import math
from dataclasses import dataclass, field

import numba as nb
import numpy as np

from perga.analytic.contact import damping_ratio, tsuji_alpha
from perga.contact.soft.laws import FASTMATH, contact_force, touching

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

HIST_XI, HIST_ACTIVE, HIST_RATE = 0, 1, 2
HIST_NORMAL_IMPULSE, HIST_TANGENTIAL_IMPULSE, HIST_DISSIPATED = 3, 4, 5
HIST_SLIP = 6
HIST_COLUMNS = 7
"""Columns of the (granule, polygon) contact history (module doc)."""

N_CHUNKS = 64
"""Granules are split into this many chunks for the parallel loop (fixed: deterministic sums)."""

_LAWS = {"linear": LINEAR, "hertz": HERTZ}

CORNER, SMOOTH_JOINT = 1, 2
"""Kinds of outline vertices (``PolygonSet.corner[:, 2]``)."""
SMOOTH_TURN = math.radians(15.0)
"""Concave joints turning by less than this (rad) split their faces' contacts at the bisector;
sharper ones (a 90° notch) keep a contact per face the disc touches."""


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
    mat (n_poly,) int32: material index (column of the ``ContactTable``);
    solid (n_vertices,) int8: 1 where the edge from this vertex to the next is on the outline
    of the body, 0 on a seam between convex pieces of one body (never a contact);
    corner (n_vertices, 3) int64: per vertex on its body's outline, the indices (into
    ``vertices``) of the outline's vertices before and after it, and its kind: ``CORNER``, a
    convex corner this polygon owns (a contact there counts while the disc centre is in the
    corner's region, between the two edges' normals); ``SMOOTH_JOINT``, a concave joint turning
    by less than ``SMOOTH_TURN`` (a face's contact there counts only on the face's side of the
    joint's bisector); 0 otherwise (−1, −1, 0 off the outline).
    Loads on each polygon: force (n_poly, 2), N; torque (n_poly,) about com, N·m; moment
    (n_poly,) about the world origin (0, 0), N·m. ``polygon_contacts`` adds to them (zero them
    with ``clear_loads`` first); ``SoftGranules.step`` sets them to the mean over its call.

    Update the pose in place before each force evaluation or call (``set_pose``), e.g. from
    Pymunk's ``body.local_to_world`` of the shape's local vertices, ``body.position`` (plus the
    rotated ``center_of_gravity``), ``body.velocity`` and ``body.angular_velocity``.
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
    solid: np.ndarray
    corner: np.ndarray
    force: np.ndarray = field(init=False)
    torque: np.ndarray = field(init=False)
    moment: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        n_poly = self.com.shape[0]
        self.force = np.zeros((n_poly, 2))
        self.torque = np.zeros(n_poly)
        self.moment = np.zeros(n_poly)

    @property
    def n_poly(self) -> int:
        """Number of polygons."""
        return int(self.com.shape[0])

    def clear_loads(self) -> None:
        """Zero the accumulated polygon forces, torques and moments."""
        self.force[:] = 0.0
        self.torque[:] = 0.0
        self.moment[:] = 0.0

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

    def arrays(self) -> tuple:
        """The geometry and inertia arrays in the order the compiled functions take them."""
        return (
            self.vertices,
            self.start,
            self.com,
            self.velocity,
            self.omega,
            self.kind,
            self.mass,
            self.inertia,
            self.pivot,
            self.mat,
            self.solid,
            self.corner,
        )

    def loads(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(force, torque, moment), the load arrays the compiled functions write."""
        return self.force, self.torque, self.moment


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
    features: tuple[np.ndarray, np.ndarray] | None = None,
) -> PolygonSet:
    """Build a ``PolygonSet`` from a list of (m_k, 2) world-vertex arrays and per-polygon data.

    Checks that each polygon has at least 3 vertices, is counter-clockwise and convex, and that
    FREE polygons have M > 0 and I_c > 0 and PINNED ones I_A > 0 (``math.inf`` is allowed and makes
    the body kinematic for the contact). Missing velocities default to zero, materials to 0.
    features: (solid, corner) over all vertices (``PolygonSet`` doc, e.g. from
    ``piece_features``); default: every polygon a whole body (all edges solid, every vertex its
    own corner).
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
    solid, corner = features if features is not None else whole_features(polys)
    n_vertices = int(start[-1])
    if solid.shape != (n_vertices,) or corner.shape != (n_vertices, 3):
        raise ValueError(f"features must have shapes ({n_vertices},) and ({n_vertices}, 3)")
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
        solid=np.ascontiguousarray(solid, dtype=np.int8),
        corner=np.ascontiguousarray(corner, dtype=np.int64),
    )


def whole_features(polygons: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(solid, corner) of polygons that are each a whole convex body (``PolygonSet`` doc)."""
    solid, corner, offset = [], [], 0
    for p in polygons:
        m = len(p)
        local = np.arange(m)
        solid.append(np.ones(m, dtype=np.int8))
        ends = offset + np.stack([(local - 1) % m, (local + 1) % m], axis=1)
        corner.append(np.column_stack([ends, np.full(m, CORNER)]))
        offset += m
    return np.concatenate(solid), np.concatenate(corner).astype(np.int64)


def piece_features(
    pieces: list[np.ndarray], loops: list[np.ndarray], rel_tol: float = 1e-9
) -> tuple[np.ndarray, np.ndarray]:
    """(solid, corner) of the convex ``pieces`` of one body whose outline is ``loops`` (each
    (n, 2), walked with the body on its left: the outer loop counter-clockwise, holes
    clockwise), vertex indices counted over the pieces concatenated (``PolygonSet`` doc).

    An edge is solid when its midpoint lies on a loop; a loop vertex where the body is convex
    (turning left) is owned by the first piece that has it; one turning right by less than
    ``SMOOTH_TURN`` is a smooth joint in every piece that has it. Lengths in any unit;
    ``rel_tol`` is relative to the body's size.
    """
    flat = np.concatenate(pieces)
    tol = rel_tol * float(np.ptp(np.concatenate(loops), axis=0).max())
    segments = np.concatenate([np.stack([q, np.roll(q, -1, axis=0)], axis=1) for q in loops])

    def index_of(point: np.ndarray) -> int:
        return int(np.argmin(np.hypot(*(flat - point).T)))

    def copies(point: np.ndarray) -> np.ndarray:
        return np.nonzero(np.hypot(*(flat - point).T) <= tol)[0]

    def on_loop(point: np.ndarray) -> bool:
        a, b = segments[:, 0], segments[:, 1]
        e = b - a
        t = np.clip(np.einsum("ij,ij->i", point - a, e) / np.einsum("ij,ij->i", e, e), 0, 1)
        return bool(np.min(np.hypot(*(a + t[:, None] * e - point).T)) <= tol)

    edges = [zip(p, np.roll(p, -1, axis=0), strict=True) for p in pieces]
    solid = np.array([on_loop(0.5 * (v + w)) for e in edges for v, w in e], dtype=np.int8)
    corner = np.tile(np.array([-1, -1, 0], dtype=np.int64), (len(flat), 1))
    for loop in loops:
        turns = zip(np.roll(loop, 1, axis=0), loop, np.roll(loop, -1, axis=0), strict=True)
        for before, vertex, after in turns:
            (ax, ay), (bx, by) = vertex - before, after - vertex
            angle = math.atan2(ax * by - ay * bx, ax * bx + ay * by)  # > 0: convex
            ends = (index_of(before), index_of(after))
            at = copies(vertex)
            if angle > 0 and len(at):
                corner[at[0]] = (*ends, CORNER)
            elif -SMOOTH_TURN < angle <= 0:
                corner[at] = (*ends, SMOOTH_JOINT)
    return solid, corner


@dataclass(frozen=True)
class ContactTable:
    """Granule-polygon contact parameters per (granule material, polygon material), SI.

    Arrays (n_granule_mat, n_polygon_mat): law (int32, LINEAR or HERTZ); k_n (N/m for LINEAR;
    (4/3)E* in Pa for HERTZ, the stiffness being k_n √r_i in N/m^{3/2}); k_t (N/m for LINEAR;
    Pa for HERTZ, the stiffness being k_t √(r_i δ) in N/m); damping (ζ for LINEAR, Tsuji α for
    HERTZ, both for the table's end criterion); friction f; clamp: 1.0 where the normal force is
    clamped at zero (end "force"), 0.0 where it may pull until the overlap closes ("overlap").
    """

    law: np.ndarray
    k_n: np.ndarray
    k_t: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    clamp: np.ndarray

    def arrays(self) -> tuple[np.ndarray, ...]:
        """(law, k_n, k_t, damping, friction, clamp), as the compiled functions take them."""
        return self.law, self.k_n, self.k_t, self.damping, self.friction, self.clamp


def contact_table(
    k_n: float | np.ndarray,
    k_t: float | np.ndarray,
    e: float | np.ndarray,
    friction: float | np.ndarray,
    law: str = "linear",
    end: str = "force",
) -> ContactTable:
    """Contact table from k_n, k_t, restitution e and friction f (scalars or (n_gm, n_pm) arrays).

    k_n, k_t: N/m (``law="linear"``) or Pa (``law="hertz"``: stiffnesses k_n √r_i and
    k_t √(r_i δ), see ``ContactTable``). The damping is tuned for the end criterion ``end``:
    ζ = damping_ratio(e, end) for ``law="linear"``, α = tsuji_alpha(e, end) for
    ``law="hertz"``; e in (e^-2, 1] for "force" (the force clamped at zero), (0, 1] for
    "overlap".
    """
    if end not in ("force", "overlap"):
        raise ValueError(f"end must be 'force' or 'overlap' (got {end!r})")
    if law not in _LAWS:
        raise ValueError(f"law must be 'linear' or 'hertz' (got {law!r})")
    arrays = np.broadcast_arrays(
        *(np.atleast_2d(np.asarray(a, dtype=np.float64)) for a in (k_n, k_t, e, friction))
    )
    kn, kt, ee, ff = (np.ascontiguousarray(a) for a in arrays)
    if np.any(kn <= 0.0) or np.any(kt < 0.0) or np.any(ff < 0.0):
        raise ValueError("need k_n > 0, k_t >= 0, friction >= 0")
    tune = damping_ratio if law == "linear" else tsuji_alpha
    damping = np.vectorize(lambda x: tune(float(x), end), otypes=[np.float64])(ee)
    return ContactTable(
        law=np.full(kn.shape, _LAWS[law], dtype=np.int32),
        k_n=kn,
        k_t=kt,
        damping=np.ascontiguousarray(damping),
        friction=ff,
        clamp=np.full(kn.shape, 1.0 if end == "force" else 0.0),
    )


def no_polygons() -> tuple[PolygonSet, ContactTable]:
    """An empty polygon set and table (what ``SoftGranules`` passes its kernel without polygons)."""
    empty = np.zeros((0, 2))
    polygons = PolygonSet(
        vertices=empty.copy(),
        start=np.zeros(1, np.int64),
        com=empty.copy(),
        velocity=empty.copy(),
        omega=np.zeros(0),
        kind=np.zeros(0, np.int32),
        mass=np.zeros(0),
        inertia=np.zeros(0),
        pivot=empty.copy(),
        mat=np.zeros(0, np.int32),
        solid=np.zeros(0, np.int8),
        corner=np.zeros((0, 3), np.int64),
    )
    table = ContactTable(
        law=np.zeros((0, 0), np.int32),
        k_n=np.zeros((0, 0)),
        k_t=np.zeros((0, 0)),
        damping=np.zeros((0, 0)),
        friction=np.zeros((0, 0)),
        clamp=np.zeros((0, 0)),
    )
    return polygons, table


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def _separation(px, py, verts, lo, hi):
    """Largest signed distance of (px, py) from the lines of the convex polygon verts[lo:hi]'s
    edges, m: a lower bound of its distance from the polygon (whatever features count)."""
    s_max = -np.inf
    for q in range(lo, hi):
        qb = q + 1 if q + 1 < hi else lo
        ex = verts[qb, 0] - verts[q, 0]
        ey = verts[qb, 1] - verts[q, 1]
        s = ((px - verts[q, 0]) * ey - (py - verts[q, 1]) * ex) / math.sqrt(ex * ex + ey * ey)
        s_max = max(s_max, s)
    return s_max


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def _past_joint(px, py, verts, corner, q):
    """(p − V)·(u_in + u_out) at the joint V = verts[q] (unit directions of the outline's edges
    into and out of V): < 0 on the incoming edge's side of the joint's bisector, > 0 beyond."""
    vx = verts[q, 0]
    vy = verts[q, 1]
    ix = vx - verts[corner[q, 0], 0]
    iy = vy - verts[corner[q, 0], 1]
    ox = verts[corner[q, 1], 0] - vx
    oy = verts[corner[q, 1], 1] - vy
    l_in = math.sqrt(ix * ix + iy * iy)
    l_out = math.sqrt(ox * ox + oy * oy)
    return (px - vx) * (ix / l_in + ox / l_out) + (py - vy) * (iy / l_in + oy / l_out)


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def closest_feature(px, py, poly, k):
    """Signed distance d of (px, py) to polygon k of ``poly`` (``PolygonSet.arrays()``; < 0
    inside) and the normal n, over the polygon's solid features only (``PolygonSet`` doc).

    Outside: d = distance to the closest point of a solid edge, n from that point to the centre;
    a closest point at a corner counts only if the polygon owns the corner and the centre lies
    in the corner's region of the whole outline, one inside an edge ending at a smooth joint
    only on the edge's side of the joint's bisector; else there is no contact (d = inf, n = 0).
    Inside: d = largest signed distance to a solid edge (≤ 0), n = that edge's outward normal.
    Returns (d, n_x, n_y), m and unit vector.
    """
    verts, start, solid, corner = poly[0], poly[1], poly[10], poly[11]
    first = last = -1
    lo = start[k]
    m = start[k + 1] - lo
    s_all = -np.inf
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
        s_all = max(s_all, s)
        if solid[lo + j] != 0 and s > s_max:
            s_max = s
            nx_max = nx
            ny_max = ny
    if s_all <= 0.0:
        if s_max == -np.inf:  # a piece with no solid edge
            return np.inf, 0.0, 0.0
        return s_max, nx_max, ny_max
    # Outside: closest point over the solid edges (segments).
    d2_min = np.inf
    qx_min = 0.0
    qy_min = 0.0
    vertex = -1
    for j in range(m):
        if solid[lo + j] == 0:
            continue
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
            vertex = lo + j if t == 0.0 else (jb if t == 1.0 else -1)
            first, last = lo + j, jb
    if d2_min == np.inf:
        return np.inf, 0.0, 0.0
    if vertex >= 0:
        if corner[vertex, 2] != CORNER:
            return np.inf, 0.0, 0.0
        vx = verts[vertex, 0]
        vy = verts[vertex, 1]
        before, after = corner[vertex, 0], corner[vertex, 1]
        into = (px - vx) * (vx - verts[before, 0]) + (py - vy) * (vy - verts[before, 1])
        out = (px - vx) * (verts[after, 0] - vx) + (py - vy) * (verts[after, 1] - vy)
        if into < 0.0 or out > 0.0:
            return np.inf, 0.0, 0.0
    elif (corner[first, 2] == SMOOTH_JOINT and _past_joint(px, py, verts, corner, first) < 0.0) or (
        corner[last, 2] == SMOOTH_JOINT and _past_joint(px, py, verts, corner, last) > 0.0
    ):
        return np.inf, 0.0, 0.0
    d = math.sqrt(d2_min)
    return d, (px - qx_min) / d, (py - qy_min) / d


@nb.njit(cache=True)
def bounding_radii(verts, start, com):
    """Radius of each polygon's bounding circle about its centre of mass, (n_poly,), m."""
    n_poly = com.shape[0]
    rho = np.zeros(n_poly)
    for k in range(n_poly):
        for q in range(start[k], start[k + 1]):
            dx = verts[q, 0] - com[k, 0]
            dy = verts[q, 1] - com[k, 1]
            rho[k] = max(rho[k], math.sqrt(dx * dx + dy * dy))
    return rho


@nb.njit(cache=True, fastmath=FASTMATH)
def pose(verts0, com0, pivot0, poly, t):
    """Pose the polygons ``poly`` (``PolygonSet.arrays()``) t seconds after the pose (verts0,
    com0, pivot0) by rigid motion at their velocities: c(t) = c0 + v_c t, vertices and pivot
    turned by ω t about c0 and moved by v_c t. Writes poly's vertices, com and pivot."""
    verts, start, com, vel, omega, _, _, _, pivot = poly[:9]
    for k in range(com.shape[0]):
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
def _end_contact(i, k, ri, mat, pmat, law, k_t, hist):
    """Reset a pair that is not touching; returns the energy of a dropped tangential spring, J."""
    if hist[i, k, HIST_ACTIVE] == 0.0:
        return 0.0
    xi = hist[i, k, HIST_XI]
    released = 0.5 * k_t[mat[i], pmat[k]] * xi * xi if law[mat[i], pmat[k]] == LINEAR else 0.0
    hist[i, k, HIST_XI] = 0.0
    hist[i, k, HIST_ACTIVE] = 0.0
    hist[i, k, HIST_RATE] = 0.0
    hist[i, k, HIST_SLIP] = 0.0
    hist[i, k, HIST_DISSIPATED] += released
    return released


@nb.njit(cache=True, inline="always", fastmath=FASTMATH)
def polygon_contact(i, k, x, v, w, r, m, mat, poly, table, rho, dt, hist):
    """Contact of granule i with polygon k over one step; updates hist[i, k] (module doc).

    Granule arrays as in ``polygon_contacts``; poly: ``PolygonSet.arrays()`` at the step's pose;
    table: ``ContactTable.arrays()``; rho: ``bounding_radii`` of the polygons. Returns
    (evaluated, fx, fy, tq, tq_poly, dissipated): whether the contact was evaluated; force on the
    granule, N (−it on the polygon); torque on the granule, N·m; torque on the polygon about its
    centre of mass, N·m; energy dissipated over the step, J.
    """
    com, pvel, pomega, kind, pmass, pinertia, pivot, pmat = poly[2:10]
    law, k_n, k_t, damping, friction, clamp = table
    xi = x[i, 0]
    yi = x[i, 1]
    ri = r[i]
    cx = xi - com[k, 0]
    cy = yi - com[k, 1]
    dist = math.sqrt(cx * cx + cy * cy)
    reach = rho[k] + ri
    # Skip when even the fastest approach cannot make it touch within the step:
    # |rate| <= 1.5 |v_i - v_p| + 0.5 |last rate|, |v_p| <= |v_c| + |w| (dist + r_i).
    if dist > reach:
        bound = 1.5 * (
            math.sqrt(v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
            + math.sqrt(pvel[k, 0] * pvel[k, 0] + pvel[k, 1] * pvel[k, 1])
            + abs(pomega[k]) * (dist + ri)
        ) + 0.5 * abs(hist[i, k, HIST_RATE])
        if dist - reach >= 0.5 * dt * bound:
            return False, 0.0, 0.0, 0.0, 0.0, _end_contact(i, k, ri, mat, pmat, law, k_t, hist)
    d, nx, ny = closest_feature(xi, yi, poly, k)
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
        return False, 0.0, 0.0, 0.0, 0.0, _end_contact(i, k, ri, mat, pmat, law, k_t, hist)
    if not active:  # a new contact: the previous one's totals are forgotten
        hist[i, k, HIST_NORMAL_IMPULSE] = 0.0
        hist[i, k, HIST_TANGENTIAL_IMPULSE] = 0.0
        hist[i, k, HIST_DISSIPATED] = 0.0
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
        kn, damp, hertz, clamp[a, b], kt, 0.0, friction[a, b],
        delta, rate, vt, m_eff, hist[i, k, HIST_XI], dt,
    )  # fmt: skip
    hist[i, k, HIST_XI] = xi_t
    hist[i, k, HIST_ACTIVE] = 1.0
    hist[i, k, HIST_RATE] = delta_dot
    hist[i, k, HIST_SLIP] = slip
    hist[i, k, HIST_NORMAL_IMPULSE] += fn * dt
    hist[i, k, HIST_TANGENTIAL_IMPULSE] += ft * dt
    hist[i, k, HIST_DISSIPATED] += dissipated
    fx = fn * nx + ft * tx
    fy = fn * ny + ft * ty
    return True, fx, fy, -arm * ft, -(rcx * fy - rcy * fx), dissipated


@nb.njit(cache=True, parallel=True, fastmath=FASTMATH)
def _polygon_contacts(x, v, w, r, m, mat, poly, table, dt, hist, f, tq, loads):
    """Compiled ``polygon_contacts`` (arrays unchecked); returns the number of contacts."""
    com = poly[2]
    force, torque, moment = loads
    n = x.shape[0]
    n_poly = com.shape[0]
    rho = bounding_radii(poly[0], poly[1], com)
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
def _candidate(i, k, x_ref, r, poly, rho, hist, reach, slack):
    """Whether pair (i, k) goes in the candidate list: in contact, or (1 − ½ dt|ω|)(d − r_i) <
    reach[k] (``candidates``), d the separation from the polygon's edge lines (a lower bound of
    the distance, so that a piece whose features do not count here now is still listed);
    slack[k] = 1 − ½ dt|ω_k|."""
    if hist[i, k, HIST_ACTIVE] != 0.0 or slack[k] <= 0.0:
        return True
    px = x_ref[i, 0]
    py = x_ref[i, 1]
    limit = r[i] + reach[k] / slack[k]
    dx = px - poly[2][k, 0]
    dy = py - poly[2][k, 1]
    if dx * dx + dy * dy >= (rho[k] + limit) ** 2:  # outside the bounding circle: cheap reject
        return False
    return _separation(px, py, poly[0], poly[1][k], poly[1][k + 1]) < limit


@nb.njit(cache=True, parallel=True)
def candidates(x_ref, r, poly, rho, hist, span, skin, dt):
    """(granule, polygon) pairs the fused step evaluates over the next ``span`` s of a call, as
    a CSR list (start (n + 1,) int64, polygon of each entry), sorted by granule then polygon.

    poly: the polygons posed now (``PolygonSet.arrays()``); x_ref: granule positions at the
    last neighbour-list build; skin: its skin, m. The kernel rebuilds that list when
    2|x − x_ref| + dt|v| would exceed the skin, so at every step |x − x_ref| + ½ dt |v| ≤ ½ skin.
    No point of polygon k moves faster than S = |v_c| + |ω| ρ, so within ``span`` the gap
    g = d − r_i between a granule and it falls by at most S·span plus the granule's
    displacement; a pair not in contact touches (``contacts.touching``, approach rate ≤
    |v_i| + |v_c| + |ω|(ρ + g)) only if (1 − ½ dt|ω|) g < ½ dt (|v_i| + |v_c| + |ω| ρ). So with
    g measured from x_ref to the polygon now, pairs with (1 − ½ dt|ω|) g ≥ ½ skin + S·span +
    ½ dt (|v_c| + |ω| ρ) are left out. Pairs in contact (``HIST_ACTIVE``) are always in, so that
    their end is evaluated.
    """
    n = x_ref.shape[0]
    velocity, omega = poly[3], poly[4]
    n_poly = omega.shape[0]
    reach = np.empty(n_poly)
    slack = np.empty(n_poly)
    for k in range(n_poly):
        top = math.sqrt(velocity[k, 0] ** 2 + velocity[k, 1] ** 2) + abs(omega[k]) * rho[k]
        reach[k] = 0.5 * skin + top * (span + 0.5 * dt)
        slack[k] = 1.0 - 0.5 * dt * abs(omega[k])
    start = np.zeros(n + 1, np.int64)
    for i in nb.prange(n):
        for k in range(n_poly):
            if _candidate(i, k, x_ref, r, poly, rho, hist, reach, slack):
                start[i + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    cpoly = np.empty(start[n], np.int64)
    for i in nb.prange(n):
        q = start[i]
        for k in range(n_poly):
            if _candidate(i, k, x_ref, r, poly, rho, hist, reach, slack):
                cpoly[q] = k
                q += 1
    return start, cpoly


@nb.njit(cache=True)
def add_loads(cpoly, ploads, com, force, torque, moment):
    """Add one step's polygon loads to force (n_poly, 2), torque and moment (n_poly,) and return
    the energy its contacts dissipated, J.

    ploads (n_entries, 4): per candidate entry (force on the polygon x, y, torque about its
    centre of mass, dissipated energy); summed in entry order (independent of the thread count);
    moment = torque + com × force about the origin at this step's com.
    """
    n_poly = com.shape[0]
    step = np.zeros((n_poly, 3))
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


@nb.njit(cache=True, parallel=True, fastmath=FASTMATH)
def _contact_energy(x, r, mat, poly, table, hist, normal, tangential):
    """Elastic energy in the granule-polygon contacts at the current poses, J (see
    ``contact_energy``)."""
    verts, start, com = poly[0], poly[1], poly[2]
    pmat = poly[9]
    law, k_n, k_t = table[0], table[1], table[2]
    rho = bounding_radii(verts, start, com)
    n = x.shape[0]
    energy = np.zeros(n)
    for i in nb.prange(n):
        for k in range(com.shape[0]):
            xi = hist[i, k, HIST_XI]
            dist = math.sqrt((x[i, 0] - com[k, 0]) ** 2 + (x[i, 1] - com[k, 1]) ** 2)
            if dist >= rho[k] + r[i] and xi == 0.0:
                continue
            d, _, _ = closest_feature(x[i, 0], x[i, 1], poly, k)
            delta = max(r[i] - d, 0.0)
            a = mat[i]
            b = pmat[k]
            if law[a, b] == LINEAR:
                spring = 0.5 * k_n[a, b] * delta * delta
                kt = k_t[a, b]
            else:
                spring = 0.4 * k_n[a, b] * math.sqrt(r[i]) * delta * delta * math.sqrt(delta)
                kt = k_t[a, b] * math.sqrt(r[i] * delta)
            if normal:
                energy[i] += spring
            if tangential:
                energy[i] += 0.5 * kt * xi * xi
    return energy.sum()


def _check(arrays: dict[str, tuple[np.ndarray, tuple[int, ...], type]]) -> None:
    for name, (arr, shape, dtype) in arrays.items():
        if arr.shape != shape or arr.dtype != dtype or not arr.flags.c_contiguous:
            raise ValueError(
                f"{name} must be C-contiguous {np.dtype(dtype).name} of shape {shape} "
                f"(got {arr.dtype.name} {arr.shape})"
            )


def check_materials(mat: np.ndarray, polygons: PolygonSet, table: ContactTable) -> None:
    """Raise ValueError unless every granule and polygon material indexes ``table``."""
    n_gm, n_pm = table.k_n.shape
    if mat.size and (mat.min() < 0 or mat.max() >= n_gm):
        raise ValueError(f"granule materials must be in [0, {n_gm})")
    if polygons.n_poly and (polygons.mat.min() < 0 or polygons.mat.max() >= n_pm):
        raise ValueError(f"polygon materials must be in [0, {n_pm})")


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
    count = _polygon_contacts(
        x, v, w, r, m, mat, polygons.arrays(), table.arrays(), float(dt), history, f, tq,
        polygons.loads(),
    )  # fmt: skip
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
    arrays = polygons.arrays(), table.arrays()
    return float(_contact_energy(x, r, mat, *arrays, history, normal, tangential))
