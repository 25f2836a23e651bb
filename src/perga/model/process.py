"""The separator as a process: granules fed over time, granules leaving through an outlet, and
granules broken by impacts, as plain SI specifications (:mod:`perga.engine.process` runs
them). Each is None in a system that does not call for it, and then costs nothing."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numba import njit

Vec2 = tuple[float, float]


@dataclass(frozen=True)
class Sizes:
    """A radius distribution as its inverse CDF: ``quantiles`` (m) at the cumulative
    probabilities ``levels`` (increasing, the last 1); ``discrete`` draws only the listed
    radii (each with the probability step up to it), else interpolates between them."""

    quantiles: tuple[float, ...]
    levels: tuple[float, ...]
    discrete: bool = False

    def draw(self, rng: np.random.Generator, count: int) -> np.ndarray:
        """``count`` radii, m."""
        u = rng.uniform(0.0, 1.0, count)
        q, c = np.asarray(self.quantiles), np.asarray(self.levels)
        if self.discrete:
            return q[np.minimum(np.searchsorted(c, u, side="right"), len(q) - 1)]
        return np.interp(u, c, q)

    @property
    def largest(self) -> float:
        """The largest radius drawn, m."""
        return max(self.quantiles)


@dataclass(frozen=True)
class FeedSpec:
    """Granules (or comb pieces) inserted at ``rate`` per s from ``start`` to ``stop`` (s), at
    most ``total``, each at a random place of the rectangle ``region`` (centre, size, angle;
    m, m, rad) where it overlaps nothing, moving at ``velocity`` (m/s). A piece is the granules
    at ``piece`` (offsets from its centre, m; one at (0, 0) for single granules), of radii from
    ``sizes``, mass ``areal_density``·πr² (kg/m²·m²) or ``mass`` (kg) each, of ``material``,
    held with ``bond_force`` (N, None: free) and ``bond_energy`` (J, ``GranuleSpec``); ``seed``
    seeds the places and sizes."""

    rate: float
    start: float
    stop: float
    total: int | None
    region: tuple[Vec2, Vec2, float]
    velocity: Vec2
    piece: tuple[Vec2, ...]
    sizes: Sizes
    areal_density: float
    mass: float | None
    material: str
    rolls: bool
    bond_force: float | None
    bond_energy: float
    seed: int

    def mass_of(self, radii: np.ndarray) -> np.ndarray:
        """Each granule's mass, kg."""
        if self.mass is not None:
            return np.full(len(radii), self.mass)
        return self.areal_density * math.pi * np.asarray(radii) ** 2


@dataclass(frozen=True)
class OutletSpec:
    """Where granules leave: ``radius`` (beyond that distance from the axis, m), ``line``
    (touching the line through ``point`` with outward unit ``normal``) or ``screen`` (the
    line's segment of ``width`` about ``point``, for granules narrower than ``aperture``)."""

    kind: Literal["radius", "line", "screen"]
    radius: float = math.inf
    point: Vec2 = (0.0, 0.0)
    normal: Vec2 = (0.0, 1.0)
    width: float = math.inf
    aperture: float = math.inf

    def leaving(self, positions: np.ndarray, radii: np.ndarray) -> np.ndarray:
        """Which granules (centres, radii; m) have reached the outlet, (n,) bool."""
        p = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
        r = np.ascontiguousarray(radii, dtype=float)
        nx, ny = self.normal
        norm = math.hypot(nx, ny)
        return _leaving(
            p, r, _KINDS.index(self.kind), self.radius, self.point[0], self.point[1],
            nx / norm, ny / norm, 0.5 * self.width, self.aperture,
        )  # fmt: skip


_KINDS = ("radius", "line", "screen")


@njit(cache=True)
def _leaving(p, r, kind, radius, px, py, nx, ny, half_width, aperture):
    """``OutletSpec.leaving`` in one compiled loop: kind 0 beyond ``radius`` of the axis; 1 the
    line through (px, py) with unit normal (nx, ny) touched or passed (d·n > −r); 2 that, within
    half_width of the point along the line, for granules narrower than ``aperture``."""
    out = np.empty(p.shape[0], dtype=np.bool_)
    for i in range(p.shape[0]):
        if kind == 0:
            out[i] = math.hypot(p[i, 0], p[i, 1]) > radius
            continue
        dx = p[i, 0] - px
        dy = p[i, 1] - py
        hit = dx * nx + dy * ny > -r[i]
        if kind == 2:
            hit = hit and abs(dy * nx - dx * ny) <= half_width and 2.0 * r[i] < aperture
        out[i] = hit
    return out


@dataclass(frozen=True)
class DamageSpec:
    """Breakage by granule-hammer impacts (Vogel & Peukert 2003): an impact of mass-specific
    energy W = ½v_n² (J/kg, v_n the normal approach speed) breaks a granule of size x (its
    diameter, m) that has had k impacts with probability from S = 1 − exp(−f_mat·x·k·(W −
    W_min)), f_mat in kg/(J·m) and W_min in J/kg; broken granules are marked or removed
    (``action``); ``seed`` seeds the draws."""

    f_mat: float
    w_min: float
    action: Literal["mark", "remove"]
    seed: int


@dataclass(frozen=True)
class ProcessSpec:
    """What of the process the system has: a feed, an outlet, damage (each None: absent)."""

    feed: FeedSpec | None = None
    outlet: OutletSpec | None = None
    damage: DamageSpec | None = None
