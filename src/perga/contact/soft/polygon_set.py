"""Convex rigid polygons for soft contacts (hammers, a drawn chamber wall): their geometry,
motion and inertia, the granule-polygon contact table and the per-contact history, SI units.

The polygons are rigid bodies moved by the caller (Pymunk); :mod:`perga.contact.soft.
polygon_forces` computes their contacts. Per polygon the caller gives its world-frame vertices
(counter-clockwise), its body's centre of mass c, linear velocity v_c and angular velocity ω
(surface velocity v_c + ω × (p − c) at a point p), and how it resists a contact impulse:

* ``FREE``: a free body of mass M and moment I_c about c: 1/m_p = 1/M + ((p − c) × n)²/I_c;
* ``PINNED``: hinged at a pivot A on a body of infinite inertia (the hammer on a kinematic rotor),
  moment I_A about A: 1/m_p = ((p − A) × n)²/I_A;
* ``KINEMATIC``: infinite inertia, 1/m_p = 0 (a wall, a rotor driven at constant ω).

Bodies of several convex pieces (a concave hammer, a chamber wall of segments): each piece is a
polygon and only the body's outline makes contacts (``solid`` and ``corner``,
:mod:`perga.geometry.disc_polygon`).

History per (granule, polygon) pair: an array (n, n_poly, HIST_COLUMNS) owned by the caller
(start from zeros; permute its rows with the granules if they are reordered), columns:

* ``HIST_XI``: ξ, the tangential spring's stretch, m;
* ``HIST_ACTIVE``: 1.0 while the contact is evaluated (``laws.touching``), else 0.0;
* ``HIST_RATE``: δ̇ of the last evaluation, m/s (not extrapolated);
* ``HIST_NORMAL_IMPULSE``: Σ F_n dt on the granule since the contact began, N·s (≥ 0);
* ``HIST_TANGENTIAL_IMPULSE``: Σ F_t dt on the granule along each step's tangent, N·s;
* ``HIST_DISSIPATED``: energy the contact dissipated since it began, J (``laws.contact_force``;
  a tangential spring dropped at the end counts too);
* ``HIST_SLIP``: slip rate v_t of the last evaluation, m/s (not extrapolated);
* ``HIST_PEAK_FORCE``: the largest normal force F_n on the granule since the contact began, N.

When a contact ends ``HIST_XI``, ``HIST_ACTIVE``, ``HIST_RATE`` and ``HIST_SLIP`` are reset to 0;
the three totals and the peak are kept until the same pair's next contact begins (they are
zeroed at its first evaluation), so a caller comparing ``HIST_ACTIVE`` before and after a call
reads the totals of the contacts that ended.
"""

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from perga.contact.laws import contact_law
from perga.geometry.pieces import whole_features
from perga.geometry.polygon import signed_area

FREE = 0
"""Polygon kind: free rigid body (mass M and moment I_c about its centre of mass)."""
PINNED = 1
"""Polygon kind: body hinged at a pivot on an infinitely heavy carrier (moment I_A about it)."""
KINEMATIC = 2
"""Polygon kind: infinite inertia (walls, a rotor at imposed ω)."""

HIST_XI, HIST_ACTIVE, HIST_RATE = 0, 1, 2
HIST_NORMAL_IMPULSE, HIST_TANGENTIAL_IMPULSE, HIST_DISSIPATED = 3, 4, 5
HIST_SLIP = 6
HIST_PEAK_FORCE = 7
HIST_COLUMNS = 8
"""Columns of the (granule, polygon) contact history (module doc)."""


class PolygonArrays(NamedTuple):
    """The arrays of a ``PolygonSet`` that compiled code reads, by the same names (its doc)."""

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
    body: np.ndarray


class PolygonLoads(NamedTuple):
    """Loads on the polygons (``PolygonSet`` doc): force (n_poly, 2), N; torque about the centre
    of mass and moment about the origin (n_poly,), N·m; recoil (n_poly, 3): m, m, rad."""

    force: np.ndarray
    torque: np.ndarray
    moment: np.ndarray
    recoil: np.ndarray


class TableArrays(NamedTuple):
    """The arrays of a ``ContactTable``, by the same names (its doc)."""

    law: np.ndarray
    k_n: np.ndarray
    k_t: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    clamp: np.ndarray
    damping_t: np.ndarray


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
    joint's bisector); 0 otherwise (−1, −1, 0 off the outline);
    body (n_poly,) int64: the first polygon of polygon k's body: polygons of one body share its
    centre of mass, velocities, kind, mass, inertia and pivot, and move as one when the
    contacts kick the body inside a call (``kernel`` doc).
    Loads on each polygon: force (n_poly, 2), N; torque (n_poly,) about com, N·m; moment
    (n_poly,) about the world origin (0, 0), N·m. ``polygon_contacts`` adds to them (zero them
    with ``clear_loads`` first); ``SoftGranules.step`` sets them to the mean over its call, and
    recoil (n_poly, 3) to how far (m, m, rad) the contacts' kicks inside the call moved the
    body's centre of mass and angle beyond its motion at the call's start velocities, less the
    last step's share (what a machine step that drifts the body at those velocities and then
    kicks it with the mean loads must add to its position to follow the call, ``kernel`` doc).

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
    body: np.ndarray
    force: np.ndarray = field(init=False)
    torque: np.ndarray = field(init=False)
    moment: np.ndarray = field(init=False)
    recoil: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        n_poly = self.com.shape[0]
        self.force = np.zeros((n_poly, 2))
        self.torque = np.zeros(n_poly)
        self.moment = np.zeros(n_poly)
        self.recoil = np.zeros((n_poly, 3))

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

    def arrays(self) -> PolygonArrays:
        """The geometry, motion and inertia arrays, as the compiled functions take them."""
        return PolygonArrays(
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
            self.body,
        )

    def outline(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(vertices, start, solid, corner): what :func:`perga.geometry.disc_polygon.
        closest_feature` takes after the point."""
        return self.vertices, self.start, self.solid, self.corner

    def loads(self) -> PolygonLoads:
        """(force, torque, moment, recoil), the load arrays the compiled functions write."""
        return PolygonLoads(self.force, self.torque, self.moment, self.recoil)


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
    body: list[int] | np.ndarray | None = None,
) -> PolygonSet:
    """Build a ``PolygonSet`` from a list of (m_k, 2) world-vertex arrays and per-polygon data.

    Checks that each polygon has at least 3 vertices, is counter-clockwise and convex, and that
    FREE polygons have M > 0 and I_c > 0 and PINNED ones I_A > 0 (``math.inf`` is allowed and makes
    the body kinematic for the contact). Missing velocities default to zero, materials to 0.
    features: (solid, corner) over all vertices (``PolygonSet`` doc, e.g. from
    ``perga.geometry.pieces.piece_features``); default: every polygon a whole body (all edges
    solid, every vertex its own corner). body: each polygon's body's first polygon (default:
    every polygon its own body).
    """
    n_poly = len(vertices)
    polys = [np.ascontiguousarray(p, dtype=np.float64) for p in vertices]
    for k, p in enumerate(polys):
        if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 3:
            raise ValueError(f"polygon {k}: vertices must be (m >= 3, 2) (got {p.shape})")
        if not signed_area(p) > 0.0:
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
        body=np.arange(n_poly, dtype=np.int64) if body is None else _bodies(body, n_poly),
    )


def _bodies(body: list[int] | np.ndarray, n_poly: int) -> np.ndarray:
    """``polygon_set``'s body array, checked: each entry names the first polygon of its body."""
    out = np.ascontiguousarray(body, dtype=np.int64).copy()
    if out.shape != (n_poly,):
        raise ValueError(f"body must have shape ({n_poly},) (got {out.shape})")
    if np.any(out < 0) or np.any(out > np.arange(n_poly)) or np.any(out[out] != out):
        raise ValueError("body: each polygon must name its body's first polygon")
    return out


@dataclass(frozen=True)
class ContactTable:
    """Granule-polygon contact parameters per (granule material, polygon material), SI.

    Arrays (n_granule_mat, n_polygon_mat): law (int32, the normal-force form LINEAR or HERTZ of
    :mod:`perga.contact.laws.row`); k_n (N/m for LINEAR; (4/3)E* in Pa for HERTZ, the stiffness
    being k_n √r_i in N/m^{3/2}); k_t (N/m for LINEAR; Pa for HERTZ, the stiffness being
    k_t √(r_i δ) in N/m); damping (the law's: ζ for LINEAR, Tsuji α for HERTZ, both for the
    table's end criterion); friction f; clamp: 1.0 where the normal force is
    clamped at zero (end "force"), 0.0 where it may pull until the overlap closes ("overlap");
    damping_t: the tangential damping ratio ζ_t (dashpot −2ζ_t√(k_t m_eff)·v_t).
    """

    law: np.ndarray
    k_n: np.ndarray
    k_t: np.ndarray
    damping: np.ndarray
    friction: np.ndarray
    clamp: np.ndarray
    damping_t: np.ndarray

    def arrays(self) -> TableArrays:
        """(law, k_n, k_t, damping, friction, clamp, damping_t), as the compiled functions take
        them."""
        return TableArrays(
            self.law, self.k_n, self.k_t, self.damping, self.friction, self.clamp, self.damping_t
        )


def contact_table(
    k_n: float | np.ndarray,
    k_t: float | np.ndarray,
    e: float | np.ndarray,
    friction: float | np.ndarray,
    law: str = "linear",
    end: str = "force",
    damping_t: float = 0.0,
) -> ContactTable:
    """Contact table from k_n, k_t, restitution e and friction f (scalars or (n_gm, n_pm) arrays)
    and one tangential damping ratio ζ_t in [0, 1).

    law: a contact law's name (:data:`perga.contact.laws.LAWS`), which gives the table its
    normal-force form and its damping from e for the end criterion ``end``
    (:meth:`~perga.contact.laws.base.ContactLaw.damping`: ζ = damping_ratio(e, end) for
    "linear", α = tsuji_alpha(e, end) for "hertz"; e in (e^-2, 1] for "force", the force
    clamped at zero, (0, 1] for "overlap"). k_n, k_t: N/m ("linear") or Pa ("hertz":
    stiffnesses k_n √r_i and k_t √(r_i δ), see ``ContactTable``).
    """
    if end not in ("force", "overlap"):
        raise ValueError(f"end must be 'force' or 'overlap' (got {end!r})")
    contact = contact_law(law)
    arrays = np.broadcast_arrays(
        *(np.atleast_2d(np.asarray(a, dtype=np.float64)) for a in (k_n, k_t, e, friction))
    )
    kn, kt, ee, ff = (np.ascontiguousarray(a) for a in arrays)
    if np.any(kn <= 0.0) or np.any(kt < 0.0) or np.any(ff < 0.0):
        raise ValueError("need k_n > 0, k_t >= 0, friction >= 0")
    if not 0.0 <= damping_t < 1.0:
        raise ValueError(f"damping_t must be in [0, 1) (got {damping_t})")
    damping = np.vectorize(lambda x: contact.damping(float(x), end), otypes=[np.float64])(ee)
    return ContactTable(
        law=np.full(kn.shape, contact.form, dtype=np.int32),
        k_n=kn,
        k_t=kt,
        damping=np.ascontiguousarray(damping),
        friction=ff,
        clamp=np.full(kn.shape, 1.0 if end == "force" else 0.0),
        damping_t=np.full(kn.shape, float(damping_t)),
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
        body=np.zeros(0, np.int64),
    )
    table = ContactTable(
        law=np.zeros((0, 0), np.int32),
        k_n=np.zeros((0, 0)),
        k_t=np.zeros((0, 0)),
        damping=np.zeros((0, 0)),
        friction=np.zeros((0, 0)),
        clamp=np.zeros((0, 0)),
        damping_t=np.zeros((0, 0)),
    )
    return polygons, table


def check_materials(mat: np.ndarray, polygons: PolygonSet, table: ContactTable) -> None:
    """Raise ValueError unless every granule and polygon material indexes ``table``."""
    n_gm, n_pm = table.k_n.shape
    if mat.size and (mat.min() < 0 or mat.max() >= n_gm):
        raise ValueError(f"granule materials must be in [0, {n_gm})")
    if polygons.n_poly and (polygons.mat.min() < 0 or polygons.mat.max() >= n_pm):
        raise ValueError(f"polygon materials must be in [0, {n_pm})")
