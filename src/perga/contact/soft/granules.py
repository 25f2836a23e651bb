"""``SoftGranules``: the arrays and parameters of a soft-granule system, stepped by the kernel."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numba
import numpy as np

from perga.analytic.contact import HertzTsuji, LinearSpringDashpot
from perga.contact.laws.row import LINEAR
from perga.contact.soft import kernel
from perga.contact.soft.laws import (
    N_PARAMS,
    P_HERTZ,
    P_KN,
    P_KT,
    contact_duration,
)
from perga.contact.soft.neighbours import build, default_skin, empty_list, remap
from perga.contact.soft.polygon_forces import contact_energy
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_ACTIVE,
    HIST_COLUMNS,
    PINNED,
    ContactTable,
    PolygonSet,
    check_materials,
    no_polygons,
)
from perga.contact.soft.threads import held_threads
from perga.geometry.disc_polygon import bounding_radii, closest_feature

if TYPE_CHECKING:
    from perga.machine.effects import FloorKick

DEFAULT_DT_FRACTION = 1.0 / 50.0
"""Default step as a fraction of the shortest contact duration (MercuryDPM convention)."""


def chamber(radius: float, centre: tuple[float, float] = (0.0, 0.0), mat: int = 0) -> np.ndarray:
    """Wall row of a round chamber of inner radius ``radius`` (m); granules inside."""
    return np.array([kernel.WALL_CHAMBER, centre[0], centre[1], radius, 0.0, mat], dtype=float)


def plane(point: tuple[float, float], normal: tuple[float, float], mat: int = 0) -> np.ndarray:
    """Wall row of a half-plane through ``point`` whose ``normal`` points into the domain."""
    nx, ny = normal
    norm = math.hypot(nx, ny)
    if not norm > 0.0:
        raise ValueError("normal must be non-zero")
    return np.array([kernel.WALL_PLANE, point[0], point[1], nx / norm, ny / norm, mat], dtype=float)


_NO_KICK = np.zeros(0)
_NOTHING_KEPT = (
    np.zeros((0, 2)),
    np.zeros((0, 2)),
    np.zeros(0),
    np.zeros((0, 2)),
    np.zeros((0, 2)),
)


def opening_of(floor: tuple[FloorKick, float] | None, kept: tuple[np.ndarray, ...] | None) -> tuple:
    """``kernel.Opening`` as a plain tuple (``SoftGranules._bundles``) for ``SoftGranules.step``'s
    ``floor`` and ``kept``."""
    kick, omega = (None, 0.0) if floor is None else floor
    return (
        0.0 if kick is None else kick.dv_max,
        float(omega) if kick is not None and kick.corotating else 0.0,
        kick is not None and kick.corotating,
        _NO_KICK if kick is None else kick.energy,
        kept is not None,
        _NOTHING_KEPT if kept is None else kept,
    )


@numba.njit(cache=True)
def looks_for_coasting(coasting: bool, pacing: np.ndarray, n_steps: int) -> bool:
    """Whether a call of ``n_steps`` steps looks for coasting granules: coasting on, no pause
    left (``pacing``, :func:`pace_coasting`) and more than one step to take at once."""
    return coasting and pacing[0] == 0 and n_steps > 1


@numba.njit(cache=True)
def pace_coasting(pacing: np.ndarray, tried: bool, coasted: int, n: int, n_steps: int) -> None:
    """After a call of ``n_steps`` steps of ``n`` granules: where it looked for coasting
    granules (``tried``) and fewer than a tenth of its granule steps coasted, do not look for
    the next 1, 2, 4, … 64 calls (looking costs about a pass over the neighbour list; the
    results are the same either way). ``pacing``: the calls left to wait, the next pause."""
    if not tried:
        pacing[0] = max(pacing[0] - 1, 0)
    elif 10 * coasted < n * n_steps:
        pacing[0] = pacing[1]
        pacing[1] = min(2 * pacing[1], 64)
    else:
        pacing[1] = 1


@numba.njit(cache=True)
def overlapping_pairs(
    x: np.ndarray,
    r: np.ndarray,
    start: np.ndarray,
    nbr: np.ndarray,
    hist: np.ndarray,
    springs: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(i, j, δ = r_i + r_j − |x_i − x_j|, list entry) of the neighbour list's (``start``,
    ``nbr``) pairs with δ > 0, with ``springs`` also those whose ``hist`` entry is non-zero;
    in list order."""
    m = nbr.size
    i, j, delta, k = (
        np.empty(m, np.int64),
        np.empty(m, np.int64),
        np.empty(m),
        np.empty(m, np.int64),
    )
    found = 0
    for a in range(start.size - 1):
        for e in range(start[a], start[a + 1]):
            b = nbr[e]
            dx, dy = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1]
            overlap = r[a] + r[b] - math.sqrt(dx * dx + dy * dy)
            if overlap > 0.0 or (springs and hist[e] != 0.0):
                i[found], j[found], delta[found], k[found] = a, b, overlap, e
                found += 1
    return i[:found], j[:found], delta[:found], k[:found]


@numba.njit(cache=True, inline="always")
def wall_overlap(x: float, y: float, r: float, wall: np.ndarray) -> float:
    """Overlap of the disc at (``x``, ``y``) of radius ``r`` (m) with the wall row ``wall``
    (``kernel``'s layout), m (≤ 0: no contact)."""
    a, b, c, d = wall[1], wall[2], wall[3], wall[4]
    if wall[0] == kernel.WALL_CHAMBER:
        return r + math.hypot(x - a, y - b) - c
    return r - ((x - a) * c + (y - b) * d)


@numba.njit(cache=True)
def wall_overlaps(x: np.ndarray, r: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """Overlaps (n, walls) of the discs (``x``, ``r``, m) with the wall rows, m
    (:func:`wall_overlap`)."""
    out = np.empty((x.shape[0], walls.shape[0]))
    for s in range(walls.shape[0]):
        for g in range(x.shape[0]):
            out[g, s] = wall_overlap(x[g, 0], x[g, 1], r[g], walls[s])
    return out


@numba.njit(cache=True)
def tally_contacts(
    n: int,
    i: np.ndarray,
    j: np.ndarray,
    delta: np.ndarray,
    walls: np.ndarray,
    active: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Per granule of ``n``: its contacts (the pairs ``i``, ``j`` with overlaps ``delta``,
    the walls it overlaps (``walls`` (n, walls), m) and its ``active`` polygon entries) and the
    largest of the pair and wall overlaps, m (0 without one)."""
    count, overlap = np.zeros(n, np.int32), np.zeros(n)
    for e in range(i.size):
        for g in (i[e], j[e]):
            count[g] += 1
            overlap[g] = max(overlap[g], delta[e])
    for g in range(n):
        for s in range(walls.shape[1]):
            if walls[g, s] > 0.0:
                count[g] += 1
            overlap[g] = max(overlap[g], walls[g, s])
        for k in range(active.shape[1]):
            count[g] += active[g, k]
    return count, overlap


def _held(a, n: int) -> np.ndarray:
    out = np.ascontiguousarray(np.asarray(a, dtype=bool).astype(np.int8))
    if out.shape != (n,):
        raise ValueError(f"held must have shape ({n},), got {out.shape}")
    return out


def _f64(a, shape) -> np.ndarray:
    out = np.ascontiguousarray(np.array(a, dtype=np.float64))
    if out.shape != shape:
        raise ValueError(f"expected shape {shape}, got {out.shape}")
    return out


class SoftGranules:
    """Soft discs with spring-dashpot contacts, integrated by ``perga.contact.soft.kernel``.

    x: positions (n, 2), m; r: radii (n,), m; m: masses (n,), kg; params: contact table
    (n_mat, n_mat, N_PARAMS) from ``perga.contact.soft.laws``; v (n, 2) m/s and w (n,) rad/s
    default to 0; mat (n,) defaults to 0; inertia defaults to the disc m r²/2; walls: rows from
    ``chamber``/``plane``; gravity (2,), m/s²; dt: step, s (default ``dt_fraction`` times the
    shortest contact duration, Hertz evaluated at approach speed v_max, m/s); skin: Verlet skin,
    m (default ``neighbours.default_skin``); threads: numba threads used (default: numba's);
    chunks: the granule-pair forces are summed in this many chunks (default: threads): the
    results depend on the chunks, never on the threads that compute them.
    polygons, polygon_table: convex rigid bodies (hammers) and the granule-polygon contact table
    (``perga.contact.soft.polygon_set``), both or neither; the granules' ``mat`` indexes the
    table's rows.
    pairs: False leaves granule-granule contacts out entirely (no neighbour list, no pair loop:
    granules pass through each other, as in a scene without granule collisions).
    held (n,) bool and bond_force (n,), N: granules held in the comb and the force that breaks
    each one's bond, and bond_energy (n,), J, the energy it takes from a blow (inf: none;
    ``kernel`` module doc); ``released_step`` (n,) is −1 until
    a granule is released, then the number of the step that released it (``steps`` counts the
    steps taken), ``release_force`` (n,) the load that did, N.

    The arrays are public and may be edited between ``step`` calls (call ``invalidate`` after
    moving granules by hand so the neighbour list is rebuilt). ``polygon_hist`` (n, n_poly,
    ``polygon_set.HIST_COLUMNS``) is the granule-polygon contact history, impact totals included;
    ``dissipated`` (3,) the energy the contact laws dissipated since the start (or ``relax``),
    J: [granule pairs, walls, polygons] (``kernel.DISSIPATED_*``); ``counts`` (2,) int64 the
    granule-polygon contacts opened or closed (a ``HIST_ACTIVE`` flag changed) and the granules
    released since the start (``kernel.COUNT_*``): a step that left them as they were changed
    no contact flag and released nothing.
    """

    def __init__(
        self,
        x,
        r,
        m,
        params: np.ndarray,
        *,
        v=None,
        w=None,
        mat=None,
        inertia=None,
        walls: Sequence[np.ndarray] | np.ndarray = (),
        gravity: tuple[float, float] = (0.0, 0.0),
        dt: float | None = None,
        dt_fraction: float = DEFAULT_DT_FRACTION,
        v_max: float = 30.0,
        skin: float | None = None,
        threads: int | None = None,
        chunks: int | None = None,
        polygons: PolygonSet | None = None,
        polygon_table: ContactTable | None = None,
        pairs: bool = True,
        held=None,
        bond_force=None,
        bond_energy=None,
    ) -> None:
        self.x = _f64(x, np.shape(x))
        n = self.x.shape[0]
        if self.x.shape != (n, 2):
            raise ValueError(f"x must have shape (n, 2), got {self.x.shape}")
        self.r = _f64(r, (n,))
        self.m = _f64(m, (n,))
        if not (np.all(self.r > 0) and np.all(self.m > 0)):
            raise ValueError("radii and masses must be > 0")
        self.v = np.zeros((n, 2)) if v is None else _f64(v, (n, 2))
        self.w = np.zeros(n) if w is None else _f64(w, (n,))
        self.inertia = 0.5 * self.m * self.r**2 if inertia is None else _f64(inertia, (n,))
        self.mat = (
            np.zeros(n, np.int32)
            if mat is None
            else np.ascontiguousarray(np.asarray(mat, dtype=np.int32))
        )
        params = np.ascontiguousarray(np.asarray(params, dtype=np.float64))
        if params.ndim != 3 or params.shape[0] != params.shape[1] or params.shape[2] != N_PARAMS:
            raise ValueError(f"params must have shape (n_mat, n_mat, {N_PARAMS})")
        if not np.allclose(params, params.transpose(1, 0, 2)):
            raise ValueError("params must be symmetric in the material pair")
        self.params = params
        walls_arr = np.array(walls, dtype=float).reshape(-1, kernel.WALL_COLUMNS)
        self.walls = np.ascontiguousarray(walls_arr)
        used = np.concatenate([self.mat, self.walls[:, 5].astype(np.int32)])
        if used.size and (used.min() < 0 or used.max() >= params.shape[0]):
            raise ValueError("a material index is outside the parameter table")
        self.wall_hist = np.zeros((n, self.walls.shape[0]))
        if (polygons is None) != (polygon_table is None):
            raise ValueError("give both polygons and polygon_table, or neither")
        self.polygons = polygons
        self.polygon_table = polygon_table
        if polygons is not None and polygon_table is not None:
            check_materials(self.mat, polygons, polygon_table)
        self._no_polygons = no_polygons()
        self.polygon_hist = np.zeros((n, self._poly[0].n_poly, HIST_COLUMNS))
        self.dissipated = np.zeros(3)
        self.counts = np.zeros(2, np.int64)
        self.held = np.zeros(n, np.int8) if held is None else _held(held, n)
        self.bond_force = np.full(n, math.inf) if bond_force is None else _f64(bond_force, (n,))
        self.bond_energy = np.full(n, math.inf) if bond_energy is None else _f64(bond_energy, (n,))
        self.released_step = np.full(n, -1, np.int64)
        self.release_force = np.full(n, math.nan)
        self.steps = 0
        self.pairs = bool(pairs)
        self.gravity = _f64(gravity, (2,))
        self.v_max = float(v_max)
        self.t_c = self.shortest_contact_duration()
        if dt is None and not math.isfinite(self.t_c):
            raise ValueError(
                f"SoftGranules: no contact can form (granules: {n}; no second granule with pairs "
                "on, no wall, no polygon), so there is no contact duration to take the step "
                "from: give dt"
            )
        self.dt = float(dt) if dt is not None else dt_fraction * self.t_c
        self._default_skin = skin is None
        self.skin = default_skin(self.r) if skin is None else float(skin)
        self.threads = numba.get_num_threads() if threads is None else int(threads)
        self.chunks = self.threads if chunks is None else max(int(chunks), 1)
        self.f = np.zeros((n, 2))
        self.tq = np.zeros(n)
        self.a_prev = np.zeros((n, 3))
        self._acc = kernel.new_accumulator(self.chunks, n)
        self.start, self.nbr, self.hist = empty_list(n)
        self.x_ref = self.x.copy()
        self._rebuild = True
        self.time = 0.0
        self.n_rebuilds = 0
        self.n_candidate_lists = 0
        """Polygon candidate lists built (``kernel.advance``), a diagnostic."""
        self.coasting = True
        """Let the granules out of every contact's reach take a call's steps at once
        (``perga.contact.soft.coasting``: the same floats as step by step)."""
        self.coasted = 0
        """Granule steps taken coasting, a diagnostic."""
        self.coast_pacing = np.array([0, 1], dtype=np.int64)
        """Calls left before coasting is looked for again, and the next pause
        (:func:`pace_coasting`)."""
        self._forget_candidates()

    @property
    def _poly(self) -> tuple[PolygonSet, ContactTable]:
        """The polygons and their table, or empty ones."""
        if self.polygons is None or self.polygon_table is None:
            return self._no_polygons
        return self.polygons, self.polygon_table

    @property
    def n(self) -> int:
        """Number of granules."""
        return self.x.shape[0]

    def shortest_contact_duration(self) -> float:
        """Shortest head-on contact duration over the material pairs present, s (inf where no
        contact can form).

        Granule pairs (that can form: with ``pairs``, two granules at least) use the two
        smallest masses and radii of their materials (m_eff grows with both masses; a Hertz
        contact of small granules is the shortest, t_c ∝ r^{3/5}), walls the smallest granule,
        polygons ``_polygon_durations``; Hertz at approach speed v_max.
        """
        if self.n == 0:
            return math.inf
        durations = []
        mats = np.unique(self.mat)
        m_min = {int(a): float(self.m[self.mat == a].min()) for a in mats}
        r_min = {int(a): float(self.r[self.mat == a].min()) for a in mats}
        count = {int(a): int(np.sum(self.mat == a)) for a in mats}
        for a in mats:
            for b in mats:
                if b < a or not self.pairs or (a == b and count[int(a)] < 2):
                    continue  # a pair that cannot form
                ma, mb = m_min[int(a)], m_min[int(b)]
                ra, rb = r_min[int(a)], r_min[int(b)]
                row = self.params[a, b]
                m_eff, r_eff = ma * mb / (ma + mb), ra * rb / (ra + rb)
                durations.append(contact_duration(row, m_eff, r_eff, self.v_max))
            for s in range(self.walls.shape[0]):
                row = self.params[a, int(self.walls[s, 5])]
                durations.append(contact_duration(row, m_min[int(a)], r_min[int(a)], self.v_max))
        return min(durations + self._polygon_durations(), default=math.inf)

    def _polygon_durations(self) -> list[float]:
        """Shortest head-on granule-polygon contact duration per polygon, s.

        The polygon's effective mass at its most yielding point (contact arm ρ, the bounding
        radius, from the centre of mass or the pivot) with the granule of smallest m_eff
        (linear) or m_eff/√r (Hertz, t_c ∝ (m_eff/(k_n √r))^{2/5}).
        """
        polys, table = self._poly
        rho = bounding_radii(polys.vertices, polys.start, polys.com)
        out = []
        for k in range(polys.n_poly):
            if polys.kind[k] == FREE:
                inv_mp = 1.0 / polys.mass[k] + rho[k] ** 2 / polys.inertia[k]
            elif polys.kind[k] == PINNED:
                arm = rho[k] + float(np.hypot(*(polys.pivot[k] - polys.com[k])))
                inv_mp = arm**2 / polys.inertia[k]
            else:
                inv_mp = 0.0
            m_eff = 1.0 / (1.0 / self.m + inv_mp)
            for a in np.unique(self.mat):
                b = int(polys.mat[k])
                mine = self.mat == a
                if table.law[a, b] == LINEAR:
                    m_min = float(m_eff[mine].min())
                    contact = LinearSpringDashpot(
                        table.k_n[a, b], table.damping[a, b], m_min, "force"
                    )
                    out.append(contact.duration)
                else:
                    i = int(np.argmin(np.where(mine, m_eff / np.sqrt(self.r), np.inf)))
                    k_hertz = table.k_n[a, b] * math.sqrt(self.r[i])
                    contact = HertzTsuji(k_hertz, table.damping[a, b], float(m_eff[i]), "force")
                    out.append(contact.impact(self.v_max).duration)
        return out

    _ROWS = (
        "x", "v", "w", "r", "m", "inertia", "mat", "held", "bond_force",
        "bond_energy", "released_step", "release_force", "f", "tq", "a_prev", "x_ref", "wall_hist",
        "polygon_hist",
    )  # fmt: skip
    """The per-granule arrays (first axis: granule), which ``add`` and ``remove`` resize."""

    def add(
        self, x, r, m, *, mat, v=None, w=None, inertia=None, held=None, bond_force=None,
        bond_energy=None,
    ) -> None:  # fmt: skip
        """Append granules (arguments as the constructor's, for the new granules only), at rest
        unless v, w are given; contacts and their histories between the others are kept."""
        x = np.asarray(x, dtype=float).reshape(-1, 2)
        k = x.shape[0]
        r, m = _f64(r, (k,)), _f64(m, (k,))
        if not (np.all(r > 0) and np.all(m > 0)):
            raise ValueError("radii and masses must be > 0")
        mat = np.asarray(mat, dtype=np.int32).reshape(k)
        if mat.size and (mat.min() < 0 or mat.max() >= self.params.shape[0]):
            raise ValueError("a material index is outside the parameter table")
        new = {
            "x": x,
            "v": np.zeros((k, 2)) if v is None else _f64(v, (k, 2)),
            "w": np.zeros(k) if w is None else _f64(w, (k,)),
            "r": r,
            "m": m,
            "inertia": 0.5 * m * r**2 if inertia is None else _f64(inertia, (k,)),
            "mat": mat,
            "held": np.zeros(k, np.int8) if held is None else _held(held, k),
            "bond_force": np.full(k, math.inf) if bond_force is None else _f64(bond_force, (k,)),
            "bond_energy": (
                np.full(k, math.inf) if bond_energy is None else _f64(bond_energy, (k,))
            ),
            "released_step": np.full(k, -1, np.int64),
            "release_force": np.full(k, math.nan),
            "f": np.zeros((k, 2)),
            "tq": np.zeros(k),
            "a_prev": np.zeros((k, 3)),
            "x_ref": x,
            "wall_hist": np.zeros((k, self.walls.shape[0])),
            "polygon_hist": np.zeros((k, *self.polygon_hist.shape[1:])),
        }
        if self.polygons is not None and self.polygon_table is not None:
            check_materials(mat, self.polygons, self.polygon_table)
        n = self.n
        for name in self._ROWS:
            old = getattr(self, name)
            setattr(
                self, name, np.ascontiguousarray(np.concatenate([old, new[name].astype(old.dtype)]))
            )
        self.start = (
            np.concatenate([self.start, np.full(k, self.start[-1])])
            if self.start.shape[0] == n + 1
            else self.start
        )
        self._resized()

    def remove(self, rows) -> float:
        """Remove the granules at ``rows``; returns the elastic energy their contacts stored, J
        (the energy those contacts take with them). The others keep their contacts."""
        rows = np.asarray(rows, dtype=np.int64)
        keep = np.ones(self.n, dtype=bool)
        keep[rows] = False
        before = self.contact_energy()
        self.start, self.nbr, self.hist = remap(self.start, self.nbr, self.hist, keep)
        for name in self._ROWS:
            setattr(self, name, np.ascontiguousarray(getattr(self, name)[keep]))
        self._resized()
        return before - self.contact_energy()

    def _resized(self) -> None:
        """After ``add``/``remove``: the accumulator, the candidate list (its rows are the old
        granules'), and the skin if it is the default."""
        self._acc = kernel.new_accumulator(self.chunks, self.n)
        self._forget_candidates()
        if self._default_skin and self.n:
            skin = default_skin(self.r)
            if skin != self.skin:
                self.skin = skin
                self._rebuild = True

    @property
    def polygon_candidates(self) -> np.ndarray:
        """The start (n + 1,) of the polygon candidate list the last call used
        (``kernel.CandidateList``; granule i's entries are start[i]:start[i + 1]), or an empty
        array where none is kept. Every pair in contact at the call's end is in it
        (``polygon_forces.candidates``)."""
        return self._listed[0]

    def _forget_candidates(self) -> None:
        """Drop the polygon candidate list the kernel keeps from call to call
        (``kernel.CandidateList``): the next call builds one."""
        polys = self._poly[0]
        empty = np.zeros(0, np.int64)
        self._listed = (empty, empty, np.zeros_like(polys.vertices), np.zeros(polys.n_poly))

    def set_threads(self, threads: int) -> None:
        """Use ``threads`` numba threads from the next step on (the chunks stay: the results
        do not change)."""
        self.threads = max(int(threads), 1)

    def invalidate(self) -> None:
        """Force a neighbour-list rebuild at the next step (after editing x or r by hand)."""
        self._rebuild = True

    def step(
        self,
        n_steps: int = 1,
        *,
        drag: float = 0.0,
        v_cap: float = math.inf,
        floor: tuple[FloorKick, float] | None = None,
        kept: tuple[np.ndarray, ...] | None = None,
    ) -> None:
        """Advance n_steps steps of dt inside one compiled kernel call (threads as configured).

        First, in the same call (``kernel.Opening``): ``floor`` = (kick, ω), the floor-friction
        kick the effects handed over (``perga.machine.effects.FloorKick``) with the rotor's
        angular velocity ω (internal units), applied to every granule; then the granules' x, v,
        w and the polygons' vertices and com copied into ``kept`` (arrays of their shapes).

        Polygons, if any, move rigidly from their current pose at their current velocities
        during the call (the PINNED pivot with them), their FREE and PINNED bodies kicked by
        each step's loads (``kernel`` doc); afterwards they hold the pose n_steps·dt later (the
        granules' time) and the velocities they came with, ``polygons.force``, ``torque``
        (about the centre of mass) and ``moment`` (about the origin) are the means over the
        call, N and N·m, and ``polygons.recoil`` what the kicks moved each body.
        ``drag`` (1/s) and ``v_cap`` (m/s) serve ``relax``; their losses are not in
        ``dissipated``.
        """
        if n_steps <= 0:
            return
        polys, table = self._poly
        if self.polygon_hist.shape != (self.n, polys.n_poly, HIST_COLUMNS):
            raise ValueError("polygon_hist does not match the granules and polygons")
        held = held_threads() == self.threads  # a run's block holds the count: no need to ask
        previous = self.threads if held else numba.get_num_threads()
        switch = previous != self.threads  # set_num_threads costs time (docs/dev/performance.md)
        if switch:
            numba.set_num_threads(self.threads)
        try:
            advance = kernel.advance_threaded if self.threaded else kernel.advance
            coast = looks_for_coasting(self.coasting, self.coast_pacing, n_steps)
            self.start, self.nbr, self.hist, rebuilt, cstart, cpoly, lists, coasted = advance(
                *self._bundles(polys, table, int(n_steps), float(drag), float(v_cap), coast),
                opening_of(floor, kept),
            )
        finally:
            if switch:
                numba.set_num_threads(previous)
        if coast or self.coast_pacing[0]:  # else the pace stays as it is
            pace_coasting(self.coast_pacing, coast, coasted, self.n, n_steps)
        self.took(1, n_steps, rebuilt, lists, coasted, cstart, cpoly)

    @property
    def threaded(self) -> bool:
        """Whether a call computes the pair forces on numba's threads."""
        return self.threads > 1 and self._acc.shape[0] > 1

    def took(
        self,
        calls: int,
        n_steps: int,
        rebuilt: int,
        lists: int,
        coasted: int,
        cstart: np.ndarray,
        cpoly: np.ndarray,
    ) -> None:
        """Book ``calls`` kernel calls of ``n_steps`` steps each (made by :meth:`step` or by
        compiled code with :meth:`call_arguments`): the rebuilds, candidate lists and coasted
        steps they counted, the candidate list (``cstart``, ``cpoly``) after the last; the
        neighbour list is the caller's to set."""
        self.coasted += coasted
        self._listed = (cstart, cpoly, *self._listed[2:])
        self._rebuild = False
        self.n_rebuilds += int(rebuilt)
        self.n_candidate_lists += int(lists)
        self.steps += calls * n_steps
        for _ in range(calls):  # call by call: the floats of calls made one at a time
            self.time += n_steps * self.dt

    def call_arguments(self, n_steps: int) -> tuple:
        """The arguments of ``kernel.advance`` but the opening, for calls of ``n_steps`` steps made
        by compiled code, which sets ``rebuild`` (after the first), ``first_step`` and ``coast``
        of each (:func:`pace_coasting`), and hands the calls to :meth:`took`."""
        polys, table = self._poly
        if self.polygon_hist.shape != (self.n, polys.n_poly, HIST_COLUMNS):
            raise ValueError("polygon_hist does not match the granules and polygons")
        return self._bundles(polys, table, int(n_steps), 0.0, math.inf)

    def _bundles(
        self,
        p: PolygonSet,
        t: ContactTable,
        n_steps: int,
        drag: float,
        v_cap: float,
        coast: bool = False,
    ) -> tuple:
        """The arguments of ``kernel.advance``: its bundles as plain tuples in their fields'
        order (``kernel.advance`` doc: they cost less to pass and to build than named ones;
        ``tests/contact/soft/test_bundles.py`` checks the order)."""
        polygons = (
            (p.vertices, p.start, p.com, p.velocity, p.omega, p.kind, p.mass, p.inertia, p.pivot,
             p.mat, p.solid, p.corner, p.body),
            (t.law, t.k_n, t.k_t, t.damping, t.friction, t.clamp, t.damping_t),
            self.polygon_hist,
            (p.force, p.torque, p.moment, p.recoil),
            self._listed,
        )  # fmt: skip
        return (
            (
                n_steps,
                self.dt,
                self.gravity,
                self.skin,
                drag,
                v_cap,
                self.pairs,
                self._rebuild,
                self.steps,
                coast,
            ),
            (self.x, self.v, self.w, self.a_prev),
            (self.r, self.m, self.inertia, self.mat),
            (
                self.held,
                self.bond_force,
                self.bond_energy,
                self.released_step,
                self.release_force,
            ),
            self.params,
            (self.walls, self.wall_hist),
            polygons,
            (self.start, self.nbr, self.hist, self.x_ref),
            (self._acc, self.f, self.tq, self.dissipated, self.counts),
        )

    # --- diagnostics (NumPy, not per step) -------------------------------------------------

    def neighbour_list(self) -> None:
        """Build the neighbour list (``start``, ``nbr``) if a build is pending (``invalidate``,
        or no step yet), so that it holds every pair within reach now."""
        if self._rebuild and self.pairs:
            self.start, self.nbr, self.hist = build(
                self.x, self.r, self.skin, self.start, self.nbr, self.hist
            )
            self.x_ref[:] = self.x
            self._forget_candidates()
            self._rebuild = False

    def _pairs(
        self, springs: bool = False
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(i, j, overlap, list entry) of the granule pairs overlapping now (δ > 0), with
        ``springs`` also those holding a tangential spring."""
        self.neighbour_list()
        if not self.pairs or self.start.shape[0] != self.n + 1:
            e = np.empty(0, np.int64)
            return e, e, np.empty(0), e
        return overlapping_pairs(self.x, self.r, self.start, self.nbr, self.hist, springs)

    def _walls_overlap(self) -> np.ndarray:
        """Overlaps (n, n_walls) of the granules with the walls, m (≤ 0: no contact)."""
        return wall_overlaps(self.x, self.r, self.walls)

    @staticmethod
    def _spring_energy(
        rows: np.ndarray,
        r_eff: np.ndarray,
        delta: np.ndarray,
        xi: np.ndarray,
        normal: bool = True,
        tangential: bool = True,
    ) -> np.ndarray:
        """Normal (over δ⁺) and/or tangential spring energy of contacts with rows ``rows``,
        effective radii ``r_eff`` (m) and tangential histories ``xi`` (the stretch, m, of a
        linear spring; the energy coordinate of a Hertz one: ``laws.tangential_force``), J."""
        delta = np.maximum(delta, 0.0)
        hertz = rows[:, P_HERTZ] != 0.0
        kn = np.where(hertz, rows[:, P_KN] * np.sqrt(r_eff), rows[:, P_KN])
        energy = np.where(hertz, 0.4 * kn * delta**2.5, 0.5 * kn * delta**2) * normal
        stored = np.where(hertz, 0.5 * xi**2, 0.5 * rows[:, P_KT] * xi**2)  # laws.spring_energy
        return energy + stored * tangential

    def contact_energy(self, *, normal: bool = True, tangential: bool = True) -> float:
        """Elastic energy stored in the normal and/or tangential springs of all contacts, J:
        granule pairs, walls and polygons (``polygon_contact_energy``).

        Normal: k δ²/2 (linear), 2 k δ^{5/2}/5 (Hertz), over overlaps δ > 0; tangential:
        k_t ξ²/2 over every spring ξ ≠ 0 (also of a contact evaluated just before first touch).
        After a step the overlaps are those at the granules' time t and the springs those updated
        by the last step, i.e. half a step earlier (kick-drift): an energy balance closes to
        O(dt²) with the normal part averaged over the step's start and end and the tangential
        part taken at its end (``tests/contact/soft/test_kernel_energy.py``).
        """
        parts = {"normal": normal, "tangential": tangential}
        i, j, delta, k = self._pairs(springs=True)
        rows = self.params[self.mat[i], self.mat[j]]
        r_eff = self.r[i] * self.r[j] / (self.r[i] + self.r[j])
        total = self._spring_energy(rows, r_eff, delta, self.hist[k], **parts).sum()
        ov = self._walls_overlap()
        for s in range(self.walls.shape[0]):
            c = np.flatnonzero((ov[:, s] > 0) | (self.wall_hist[:, s] != 0))
            rows = self.params[self.mat[c], int(self.walls[s, 5])]
            springs = self._spring_energy(rows, self.r[c], ov[c, s], self.wall_hist[c, s], **parts)
            total += springs.sum()
        return float(total) + self.polygon_contact_energy(**parts)

    def polygon_contact_energy(self, *, normal: bool = True, tangential: bool = True) -> float:
        """Elastic energy stored in the granule-polygon contacts at the polygons' current pose, J
        (``polygon_forces.contact_energy``; after ``step`` that pose is at the granules' time)."""
        polys, table = self._poly
        return contact_energy(
            self.x, self.r, self.mat, polys, table, self.polygon_hist, normal, tangential
        )

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy, J."""
        return float(
            0.5 * np.sum(self.m * np.sum(self.v**2, axis=1))
            + 0.5 * np.sum(self.inertia * self.w**2)
        )

    def potential_energy(self) -> float:
        """Potential energy in the uniform gravity field, −Σ m g·x, J."""
        return float(-np.sum(self.m * (self.x @ self.gravity)))

    def energy(self) -> float:
        """Kinetic + gravitational + elastic contact energy, J."""
        return self.kinetic_energy() + self.potential_energy() + self.contact_energy()

    def contact_counts(self) -> tuple[np.ndarray, np.ndarray]:
        """Per granule, the number of its contacts now and the largest of their overlaps, m:
        (counts (n,) int32, overlaps (n,) float64, 0 without a contact).

        Contacts: granule pairs and walls with overlap δ > 0, and polygons whose contact the
        kernel holds active (``polygon_hist[:, :, HIST_ACTIVE] != 0``, which may begin half a
        step before first touch) with overlap r − d, d from ``closest_feature`` at the granule's
        centre. Builds the neighbour list first if a build is pending (``invalidate``, or no
        step yet).
        """
        i, j, delta, _ = self._pairs()
        active = self.polygon_hist[:, :, HIST_ACTIVE] != 0.0
        count, overlap = tally_contacts(self.n, i, j, delta, self._walls_overlap(), active)
        outline = self._poly[0].outline()
        for a, k in zip(*np.nonzero(active), strict=True):
            d, _, _ = closest_feature(self.x[a, 0], self.x[a, 1], *outline, k)
            overlap[a] = max(overlap[a], self.r[a] - d)
        return count, overlap

    def max_overlap(self) -> float:
        """Largest overlap of any granule with a granule or wall, m (0 with no contact)."""
        _, _, delta, _ = self._pairs()
        ov = self._walls_overlap()
        return float(max(delta.max(initial=0.0), ov.max(initial=0.0), 0.0))

    def release_speed(self) -> float:
        """Largest speed a single contact's stored normal energy could give, √(2E_c/m_eff), m/s."""
        i, j, delta, _ = self._pairs()
        rows = self.params[self.mat[i], self.mat[j]]
        m_eff = self.m[i] * self.m[j] / (self.m[i] + self.m[j])
        r_eff = self.r[i] * self.r[j] / (self.r[i] + self.r[j])
        e = self._spring_energy(rows, r_eff, delta, np.zeros_like(delta))
        speeds = [np.sqrt(2.0 * e / m_eff)]
        ov = self._walls_overlap()
        for s in range(self.walls.shape[0]):
            c = np.flatnonzero(ov[:, s] > 0)
            rows = self.params[self.mat[c], int(self.walls[s, 5])]
            e = self._spring_energy(rows, self.r[c], ov[c, s], np.zeros(c.size))
            speeds.append(np.sqrt(2.0 * e / self.m[c]))
        return float(max(s.max(initial=0.0) for s in speeds))

    def relax(
        self,
        *,
        v_release: float = 0.01,
        v_cap: float | None = None,
        drag: float | None = None,
        block: int = 200,
        max_steps: int = 200_000,
    ) -> int:
        """Remove initial overlaps gently before a run; returns the steps used.

        Runs the normal kernel with a global drag (default π/t_c, about the contact's own ω_n)
        and a speed cap (default 0.05 r_min/t_c: a granule moves at most 5 % of its radius per
        contact duration), in blocks of ``block`` steps, until no contact stores more normal
        energy than would launch its pair at v_release (m/s) and no granule moves faster than
        v_release; then zeroes velocities, spins, tangential springs, the polygon contact history
        and ``dissipated``. Polygons are held at rest meanwhile (their velocities are restored
        afterwards); overlaps with them are not part of the release criterion. Without it a
        densely overlapping packing explodes (docs/dev/validation.md). Raises RuntimeError after
        max_steps.
        """
        drag = math.pi / self.t_c if drag is None else drag
        v_cap = 0.05 * float(self.r.min()) / self.t_c if v_cap is None else v_cap
        polys = self._poly[0]
        motion = polys.velocity.copy(), polys.omega.copy()
        polys.velocity[:] = 0.0
        polys.omega[:] = 0.0
        steps = 0
        try:
            while True:
                speed = float(np.sqrt(np.max(np.sum(self.v**2, axis=1), initial=0.0)))
                if self.release_speed() <= v_release and speed <= v_release:
                    break
                if steps >= max_steps:
                    raise RuntimeError(
                        f"relax: overlaps not resolved after {steps} steps (release speed "
                        f"{self.release_speed():.3g} m/s); the packing may be too dense"
                    )
                self.step(block, drag=drag, v_cap=v_cap)
                steps += block
        finally:
            polys.velocity[:], polys.omega[:] = motion
        self.v[:] = 0.0
        self.w[:] = 0.0
        self.hist[:] = 0.0
        self.wall_hist[:] = 0.0
        self.counts[kernel.COUNT_CONTACT_CHANGES] += np.count_nonzero(
            self.polygon_hist[:, :, HIST_ACTIVE]
        )
        self.polygon_hist[:] = 0.0
        self.dissipated[:] = 0.0
        self.time = 0.0
        return steps


__all__ = ["DEFAULT_DT_FRACTION", "SoftGranules", "chamber", "plane"]
