"""Where the granules start: positions (m) and velocities (m/s) from a case's placement.

numpy and scipy, no Pymunk: the cross-checks and the mapping to the system share it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from perga.case.schema import (
    Case,
    CombPlacement,
    ExplicitPlacement,
    RandomPlacement,
    RingPlacement,
    ShotPlacement,
)
from perga.geometry.clearance import BoolArray, Obstacles
from perga.model.hammer_geometry import hammer_geometry
from perga.model.obstacles import initial_obstacles
from perga.model.parts import chamber_spec, hammer_angles
from perga.model.sizes import initial_radii

FloatArray = NDArray[np.float64]

MAX_ATTEMPTS_PER_GRANULE = 1000
"""Random sequential addition gives up after this many rejected tries per granule on average."""


class PlacementError(ValueError):
    """The placement cannot be realised (e.g. the random pack does not fit)."""


def ring(count: int, radius: float, phase: float) -> FloatArray:
    """``count`` points evenly spaced on a circle of ``radius`` (m), the first at ``phase``."""
    angles = phase + 2 * math.pi * np.arange(count) / count
    return radius * np.column_stack((np.cos(angles), np.sin(angles)))


CANDIDATE_BATCH = 1024
"""Candidate centres drawn at a time."""

WINDOW = 16
"""Discs placed from one test of the candidates left in a batch (:meth:`_Pack.window`)."""


class _Pack:
    """A random pack under way: the discs of ``radii`` (m) placed so far, clear of each other
    and of the ``obstacles``. A cell grid (cells of twice the largest radius) tests one
    candidate exactly; a k-d tree of most placed discs and one call of the obstacles test many
    candidates at once, refusing only those the exact test would refuse."""

    def __init__(self, radii: FloatArray, obstacles: Obstacles | None) -> None:
        self.radii, self.obstacles = radii, obstacles
        self.cell = 2 * float(np.max(radii)) if len(radii) else 1.0
        self.centres = np.empty((len(radii), 2))
        self.count = 0
        self.grid: dict[tuple[int, int], list[int]] = {}
        self.tree: cKDTree | None = None
        self.in_tree = 0

    @property
    def full(self) -> bool:
        """Whether every disc is placed."""
        return self.count == len(self.radii)

    def batch(self, points: FloatArray) -> None:
        """Place the next discs, each at the first of ``points`` (m, in order, each tried once)
        where it overlaps nothing, until the points or the discs run out."""
        start = 0
        while start < len(points) and not self.full:
            start = self.window(points, start)

    def window(self, points: FloatArray, start: int) -> int:
        """Place up to ``WINDOW`` discs at ``points[start:]``: those points first tested at once
        at the smallest of their radii (:meth:`blocked`, the obstacles), the rest one by one
        (the obstacles again at a larger radius); the index of the first point not tried."""
        first, rest = self.count, points[start:]
        smallest = float(self.radii[first : first + WINDOW].min())
        free = ~self.blocked(rest, smallest)
        if self.obstacles is not None:
            free[free] = self.obstacles.clear(rest[free], np.full(np.count_nonzero(free), smallest))
        candidates = np.flatnonzero(free)
        clear_for, clear = smallest, np.ones(len(candidates), dtype=bool)
        for i, j in enumerate(candidates):
            (x, y), radius = rest[j], self.radii[self.count]
            if self.overlaps(x, y, radius):
                continue
            if self.obstacles is not None and radius != clear_for:
                clear_for = radius
                left = rest[candidates[i:]]
                clear[i:] = self.obstacles.clear(left, np.full(len(left), radius))
            if not clear[i]:
                continue
            self.add(x, y)
            if self.full or self.count == first + WINDOW:
                return start + j + 1
        return len(points)

    def overlaps(self, x: float, y: float, radius: float) -> bool:
        """Whether a disc of ``radius`` at (x, y) overlaps a placed one (exact)."""
        ci, cj = math.floor(x / self.cell), math.floor(y / self.cell)
        c, r = self.centres, self.radii
        return any(
            (c[k, 0] - x) ** 2 + (c[k, 1] - y) ** 2 < (radius + r[k]) ** 2
            for di in (-1, 0, 1)
            for dj in (-1, 0, 1)
            for k in self.grid.get((ci + di, cj + dj), ())
        )

    def add(self, x: float, y: float) -> None:
        """Place the next disc at (x, y)."""
        cell = (math.floor(x / self.cell), math.floor(y / self.cell))
        self.grid.setdefault(cell, []).append(self.count)
        self.centres[self.count] = x, y
        self.count += 1

    def blocked(self, points: FloatArray, smallest: float) -> BoolArray:
        """Points where a disc of radius >= ``smallest`` (m) overlaps a placed one: nearer the
        nearest disc in the tree than ``smallest`` plus the smallest placed radius (less a
        relative 1e-9: round-off never refuses a point the exact test takes). The tree is
        rebuilt once the discs placed since it outnumber a sixteenth of it."""
        if self.count - self.in_tree > self.in_tree // 16:
            self.in_tree = self.count
            self.tree = cKDTree(self.centres[: self.count])
        if self.tree is None:
            return np.zeros(len(points), dtype=bool)
        distance, _ = self.tree.query(points, k=1)
        return distance < (smallest + float(self.radii[: self.in_tree].min())) * (1 - 1e-9)


def random_pack(
    radii: FloatArray, inner: float, outer: float, seed: int, obstacles: Obstacles | None = None
) -> FloatArray:
    """Non-overlapping discs of ``radii`` (m) with centres uniform in the annulus
    inner ≤ r ≤ outer (m), clear of the ``obstacles`` (hammers, the chamber), by random
    sequential addition: each candidate centre, drawn ``CANDIDATE_BATCH`` at a time from the
    numbers of ``sqrt(rng.uniform(inner², outer²))`` and ``rng.uniform(0, 2π)`` in turn, is the
    next disc's if that disc overlaps nothing there (:class:`_Pack`).

    Deterministic for a given seed. Raises :class:`PlacementError` when it cannot place them
    all within ``MAX_ATTEMPTS_PER_GRANULE`` candidates per disc.
    """
    rng = np.random.default_rng(seed)
    count, limit = len(radii), MAX_ATTEMPTS_PER_GRANULE * len(radii)
    pack = _Pack(radii, obstacles)
    lo, span = inner**2, outer**2 - inner**2
    attempts = 0
    while not pack.full:
        if attempts >= limit:
            raise PlacementError(
                f"random placement fitted only {pack.count} of {count} granules (radii up to "
                f"{pack.cell / 2:g} m) in the annulus [{inner:g}, {outer:g}] m clear of the "
                "hammers and the wall: use fewer granules or a wider annulus"
            )
        u = rng.random(2 * CANDIDATE_BATCH)
        distance, theta = np.sqrt(lo + span * u[0::2]), 2 * math.pi * u[1::2]
        points = np.array(
            [(d * math.cos(t), d * math.sin(t)) for d, t in zip(distance, theta, strict=True)]
        )
        pack.batch(points[: limit - attempts])
        attempts += len(points)
    return pack.centres


def comb(placement: CombPlacement) -> FloatArray:
    """The cell centres of a comb piece, (rows·columns, 2), m: rows of cells ``pitch`` apart,
    rows √3/2·pitch apart and every other one shifted by pitch/2, centred and turned."""
    j, i = np.divmod(np.arange(placement.rows * placement.columns), placement.columns)
    x = (i + 0.5 * (j % 2)) * placement.pitch
    y = j * placement.pitch * math.sqrt(3.0) / 2.0
    x, y = x - 0.5 * (x.min() + x.max()), y - 0.5 * (y.min() + y.max())
    c, s = math.cos(placement.angle), math.sin(placement.angle)
    cx, cy = placement.centre
    return np.column_stack((cx + c * x - s * y, cy + s * x + c * y))


def face(case: Case) -> tuple[float, float, float]:
    """Hammer 0's leading face in the hammer's frame, m: (x_start, x_end, y) of the outline's
    edge of largest y."""
    outline = np.asarray(hammer_geometry(case).outline, dtype=float)
    y = float(outline[:, 1].max())
    on_face = outline[np.isclose(outline[:, 1], y, rtol=0, atol=1e-9 * np.ptp(outline))]
    return float(on_face[:, 0].min()), float(on_face[:, 0].max()), y


class ShotFace(NamedTuple):
    """The face a shot is fired at, fixed frame, SI: the point its path meets, the face's
    unit normal n (towards the granule) and tangent a, and the face's velocity there."""

    point: FloatArray
    normal: FloatArray
    tangent: FloatArray
    velocity: FloatArray


def shot_face(case: Case, placement: ShotPlacement) -> ShotFace:
    """The face of ``placement`` at t = 0 (:class:`~perga.case.schema.ShotPlacement`): hammer
    0's leading face (a the hammer's axis, the face turning with the rotor), or the chamber
    wall's edge that the ray from the axis at ``at`` meets (a counter-clockwise, at rest)."""
    if placement.target == "wall":
        return _wall_face(case, 0.0 if placement.at is None else placement.at)
    x0, x1, y = face(case)
    along = 0.5 * (x0 + x1) if placement.along is None else placement.along
    phi = hammer_angles(case)[0]
    axis_angle = phi + case.hammers.swing_angle
    hinge = case.hammers.hinge_radius * np.array([math.cos(phi), math.sin(phi)])
    a = np.array([math.cos(axis_angle), math.sin(axis_angle)])
    n = np.array([-a[1], a[0]])
    point = hinge + along * a + y * n
    omega = case.rotor.angular_velocity
    return ShotFace(point, n, a, omega * np.array([-point[1], point[0]]))


def _wall_face(case: Case, at: float) -> ShotFace:
    """The chamber's inner edge met by the ray from the axis at angle ``at`` (rad), nearest
    first; its inward normal and counter-clockwise tangent."""
    if case.chamber is None:
        raise PlacementError("granules.placement: target = 'wall' needs a [chamber]")
    outline = chamber_spec(case).inner_outline()  # counter-clockwise
    ray = np.array([math.cos(at), math.sin(at)])
    best = None
    for p, q in zip(outline, np.roll(outline, -1, axis=0), strict=True):
        edge = q - p
        denominator = ray[0] * edge[1] - ray[1] * edge[0]
        if denominator == 0:
            continue
        t = (p[0] * edge[1] - p[1] * edge[0]) / denominator  # along the ray
        u = (p[0] * ray[1] - p[1] * ray[0]) / denominator  # along the edge
        if t > 0 and 0 <= u <= 1 and (best is None or t < best[0]):
            best = (t, edge / np.hypot(*edge))
    if best is None:
        raise PlacementError(f"granules.placement: no wall edge meets the ray at {at} rad")
    t, a = best
    return ShotFace(t * ray, np.array([-a[1], a[0]]), a, np.zeros(2))


def shot(case: Case, placement: ShotPlacement) -> tuple[FloatArray, FloatArray]:
    """(position, velocity), (1, 2) each, SI, of a granule fired at its face
    (:func:`shot_face`): its path d = −cos θ n + sin θ a (θ the angle of incidence) meets the
    face after ``gap``, and its velocity is the face's there plus ``speed``·d."""
    f = shot_face(case, placement)
    theta = placement.incidence
    d = -math.cos(theta) * f.normal + math.sin(theta) * f.tangent
    centre = f.point + case.granules.radius * f.normal - d * placement.gap / math.cos(theta)
    return centre[None, :], (f.velocity + placement.speed * d)[None, :]


def held(case: Case) -> bool:
    """Whether the granules start held in comb cells: a comb whose material has a
    detachment force."""
    placement = case.granules.placement
    material = case.materials.get(case.granules.material)
    return isinstance(placement, CombPlacement) and bool(material and material.detachment_force)


def initial_spins(case: Case) -> FloatArray:
    """Every granule's angular velocity at t = 0, rad/s: a shot's spin, an explicit
    placement's, else 0."""
    placement = case.granules.placement
    if isinstance(placement, ExplicitPlacement) and placement.angular_velocities is not None:
        return np.array(placement.angular_velocities, dtype=float)
    spin = placement.spin if isinstance(placement, ShotPlacement) else 0.0
    return np.full(case.granules.count, spin)


def initial_state(case: Case) -> tuple[FloatArray, FloatArray]:
    """(positions, velocities), shapes (n, 2), SI, of every granule at t = 0 (at rest unless the
    explicit placement gives velocities or the granule is a shot). Raises ValueError if the case
    has no placement."""
    g, placement = case.granules, case.granules.placement
    if isinstance(placement, ShotPlacement):
        return shot(case, placement)
    if isinstance(placement, ExplicitPlacement):
        positions = np.array(placement.positions, dtype=float)
        velocities = (
            np.array(placement.velocities, dtype=float)
            if placement.velocities
            else np.zeros_like(positions)
        )
        return positions, velocities
    if isinstance(placement, RingPlacement):
        positions = ring(g.count, placement.radius, placement.phase)
    elif isinstance(placement, CombPlacement):
        positions = comb(placement)
    elif isinstance(placement, RandomPlacement):
        positions = random_pack(
            initial_radii(case),
            placement.inner_radius,
            placement.outer_radius,
            case.solver.seed if placement.seed is None else placement.seed,
            initial_obstacles(case),
        )
    else:
        raise ValueError("granules.placement is missing: a simulation needs start positions")
    return positions, np.zeros_like(positions)
