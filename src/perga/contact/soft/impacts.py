"""Granule-hammer impacts of soft granules, as :class:`~perga.model.records.Impact` rows.

A soft impact lasts many granule steps. Between Pymunk steps the log compares each
(granule, hammer) pair's contact flag in the kernel's polygon history: a pair that became active
starts an impact (the granule's state before the Pymunk step, the hammer's kinetic energy, the
contact normal from the closest feature of the hammer's outline and the relative velocity of
the contact points), a pair that became inactive completes it (the state after, and the
kernel's per-contact totals: normal and tangential impulse, energy dissipated, the peak normal
force and, for a Hertz contact, the peak pressure it gives, ``hertz_peak_pressure``). Normal and
tangent turn with the hammer between start and end (they are fixed in the hammer's frame).
An impact is written when it ends; its ``time`` is the end of the Pymunk step in which it began.
With it the log writes the contact as a :class:`~perga.model.records.Contact`: its first state
the granule's before that step, its last the granule's after the step in which it ended.
The velocities and energies of all the contacts a look opens or closes are computed in one
compiled call (``_contact_motion``), the hammers' states once per look.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, NamedTuple

import numba
import numpy as np

from perga.contact.laws.row import LINEAR
from perga.contact.soft import SoftGranules
from perga.contact.soft.granules import wall_overlap
from perga.contact.soft.kernel import COUNT_CONTACT_CHANGES
from perga.contact.soft.polygon_set import (
    HIST_ACTIVE,
    HIST_DISSIPATED,
    HIST_NORMAL_IMPULSE,
    HIST_PEAK_FORCE,
)
from perga.geometry.disc_polygon import FASTMATH, closest_feature
from perga.machine import units as u
from perga.model.records import Contact, HammerState, Impact

if TYPE_CHECKING:
    from perga.machine.machine import MachineState


class _Start(NamedTuple):
    """An open impact's values at its start (:meth:`SoftImpactLog._start`)."""

    time: float
    normal: tuple[float, float]
    edge: tuple[float, float]
    normal_velocity: float
    tangential_velocity: float
    point: tuple[float, float]
    position: tuple[float, float]
    granule_energy: float
    granule_velocity: tuple[float, float]
    granule_spin: float
    held: bool
    others: int
    hammer: HammerState


def hertz_peak_pressure(force: float, k_n: float, radius: float) -> float:
    """Hertz's peak contact pressure, Pa, of a sphere of ``radius`` (m) on a flat under the
    normal ``force`` (N) of the law F = k_n·√R·δ^{3/2} (k_n = (4/3)E*, Pa): the overlap
    δ = (F/(k_n√R))^{2/3}, contact radius a = √(Rδ), p0 = 3F/(2πa²) = (2E*/π)·√(δ/R)
    (Johnson, Contact Mechanics, 1985, §4.2)."""
    if not force > 0.0:
        return 0.0
    delta = (force / (k_n * math.sqrt(radius))) ** (2.0 / 3.0)
    return 3.0 * force / (2.0 * math.pi * radius * delta)


def _first_edge(vertices: np.ndarray, start: np.ndarray, k: int) -> tuple[float, float]:
    """The first edge of polygon k (vertices ``vertices[start[k]:start[k + 1]]``), m."""
    a, b = vertices[start[k]], vertices[start[k] + 1]
    return (float(b[0] - a[0]), float(b[1] - a[1]))


def _turn(before: tuple[float, float], after: tuple[float, float]) -> float:
    """The angle (rad, in (−π, π]) through which a body whose edge ``before`` became ``after``
    turned."""
    return math.atan2(
        before[0] * after[1] - before[1] * after[0], before[0] * after[0] + before[1] * after[1]
    )


def _turned(
    n: tuple[float, float], before: tuple[float, float], after: tuple[float, float]
) -> tuple[float, float]:
    """``n`` turned as a body whose edge ``before`` became ``after`` turned."""
    angle = _turn(before, after)
    c, s = math.cos(angle), math.sin(angle)
    return (c * n[0] - s * n[1], s * n[0] + c * n[1])


class SoftImpactLog:
    """Impacts of ``granules`` on the hammers, polygon k of ``granules.polygons`` being a piece
    of hammer ``hammer_of[k]`` (−1: not a hammer; a contact with each piece is an impact of
    its own); hand :meth:`kept` to every kernel call (it copies the start state there), call
    :meth:`after` after it, and :meth:`rows_changed` when granules are added or removed.
    ``hammer_state(h, machine)`` gives hammer h's :class:`~perga.model.records.HammerState` now
    (``machine``: the machine's state now), ``ids()`` the id of each granule row;
    ``movable[h]``: whether hammer h's body moves under contacts (not carried by a rotor of
    prescribed speed); ``dt``: the machine step, s. An impact's other contacts are counted at
    its start and its end."""

    def __init__(
        self,
        granules: SoftGranules,
        hammer_of: np.ndarray,
        hammer_state: Callable[[int, MachineState], HammerState],
        ids: Callable[[], np.ndarray],
        movable: np.ndarray,
        dt: float,
    ) -> None:
        self.impacts: list[Impact] = []
        self.contacts: list[Contact] = []
        self._dt = dt
        self._g = granules
        self._ids = ids
        self._hammer_of = hammer_of
        self._hammer_state = hammer_state
        self._movable = movable
        self._active = granules.polygon_hist[:, :, HIST_ACTIVE] != 0.0
        self._seen = int(granules.counts[COUNT_CONTACT_CHANGES])
        self._changes = np.empty((0, 3), dtype=np.int64)
        self._is_hammer = hammer_of >= 0
        self._open: dict[tuple[int, int], _Start] = {}  # (granule id, polygon)
        self._ids_before = ids().copy()
        self._x = granules.x.copy()
        self._v = granules.v.copy()
        self._w = granules.w.copy()
        self._vertices = granules.polygons.vertices.copy()
        self._com = granules.polygons.com.copy()

    def kept(self) -> tuple[np.ndarray, ...]:
        """The arrays into which the next kernel call copies the granules' x, v, w and the
        polygons' vertices and com at its start (``kernel.Opening``; starts need them), of
        their shapes."""
        g = self._g
        if self._x.shape != g.x.shape:
            self._x, self._v, self._w = np.empty_like(g.x), np.empty_like(g.v), np.empty_like(g.w)
        return self._x, self._v, self._w, self._vertices, self._com

    def rows_changed(self, keep: np.ndarray, added: int) -> None:
        """Granule rows were removed (``keep``: the old rows that stay) and ``added`` appended:
        the contacts of removed granules are forgotten."""
        gone = set(int(i) for i in self._ids_before[~keep]) if (~keep).any() else set()
        self._open = {key: v for key, v in self._open.items() if key[0] not in gone}
        self._active = np.vstack(
            [self._active[keep], np.zeros((added, self._active.shape[1]), dtype=bool)]
        )
        self._ids_before = self._ids().copy()

    def after(self, time: float, machine: MachineState, hammer_rows: np.ndarray) -> None:
        """Open and close impacts after a kernel call; ``time``: end of the step, s; ``machine``
        the machine now, hammer h's body in its row ``hammer_rows[h]``. The flags are compared
        only when the kernel counted a change since the last look (``SoftGranules.counts``);
        the contacts closed are completed first, then those opened are started, each in row
        order."""
        g = self._g
        seen = int(g.counts[COUNT_CONTACT_CHANGES])
        if seen == self._seen:
            return
        self._seen = seen
        if self._changes.shape[0] < self._active.size:
            self._changes = np.empty((self._active.size, 3), dtype=np.int64)
        count = _contact_changes(
            g.polygon_hist, self._active, self._is_hammer, g.polygon_candidates, self._changes
        )
        if count == 0:
            return
        changes = self._changes[:count].tolist()
        ids = self._ids()
        closed = [(i, k) for i, k, opened in changes if not opened]
        opened = [(i, k) for i, k, opened in changes if opened]
        if closed:
            self._close(closed, ids, self._hammer_motion(machine, hammer_rows), time)
        if opened:
            self._start(opened, ids, time, machine)

    def _start(
        self,
        opened: list[tuple[int, int]],
        ids: np.ndarray,
        time: float,
        machine: MachineState,
    ) -> None:
        """Start an impact for each (granule row, polygon) of ``opened``: the granule's state
        and the polygon's pose before the call (with the direction of its first edge there, to
        turn the normal with it at the end), the hammer's state now (``machine``)."""
        g, p = self._g, self._g.polygons
        rows = np.array(opened, dtype=np.int64).reshape(-1, 2)
        normals = _start_normals(
            rows, self._x, self._vertices, g.x, p.vertices, p.start, p.solid, p.corner
        )
        motion = _contact_motion(
            rows, normals, self._x, self._v, self._w, g.r, g.m, g.inertia, self._com,
            p.velocity, p.omega,
        ).tolist()  # fmt: skip
        hammers: dict[int, HammerState] = {}
        others = self._others(opened)
        for (i, k), (nx, ny), (vn, vt, px, py, energy), other in zip(
            opened, normals.tolist(), motion, others, strict=True
        ):
            hammer = int(self._hammer_of[k])
            if hammer not in hammers:
                hammers[hammer] = self._hammer_state(hammer, machine)
            self._open[(int(ids[i]), k)] = _Start(
                time=time,
                normal=(nx, ny),
                edge=_first_edge(self._vertices, p.start, k),
                normal_velocity=vn,
                tangential_velocity=vt,
                point=(px, py),
                position=(float(self._x[i, 0]), float(self._x[i, 1])),
                granule_energy=energy,
                granule_velocity=(float(self._v[i, 0]), float(self._v[i, 1])),
                granule_spin=float(self._w[i]),
                held=bool(self._g.held[i]),
                others=other,
                hammer=hammers[hammer],
            )

    def _others(self, contacts: list[tuple[int, int]]) -> list[int]:
        """For each (granule row, polygon): the granule's contacts now but those with the
        polygon's hammer, and, if that hammer moves under contacts, the other granules' contacts
        with it (:func:`_other_contacts`)."""
        g = self._g
        g.neighbour_list()
        pairs = np.array(contacts, dtype=np.int64).reshape(-1, 2)
        return _other_contacts(
            pairs, self._hammer_of, self._movable, g.x, g.r, g.start, g.nbr, g.pairs,
            np.ascontiguousarray(g.polygon_hist[:, :, HIST_ACTIVE]), g.walls,
        ).tolist()  # fmt: skip

    def _hammer_motion(
        self, machine: MachineState, hammer_rows: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each polygon's centre of mass where the kernel call left it (m: its pose at the
        granules' time, where the next call starts) and its hammer body's velocity (m/s) and
        angular velocity (rad/s) in ``machine``, the state the next call starts from (the
        wall's polygons take the first hammer's: never read)."""
        rows = hammer_rows[np.maximum(self._hammer_of, 0)]
        return (
            self._g.polygons.com,
            machine.velocity[rows] * u.VELOCITY,
            machine.omega[rows] * u.ANGULAR_VELOCITY,
        )

    def _close(
        self,
        closed: list[tuple[int, int]],
        ids: np.ndarray,
        hammers_now: tuple[np.ndarray, np.ndarray, np.ndarray],
        time: float,
    ) -> None:
        """Complete the impact of each (granule row, polygon) of ``closed``: the granule's
        state now relative to its hammer's motion now (``hammers_now``, ``_hammer_motion``:
        as the next kernel call will see it, as the start of an impact takes it from the call
        it begins in; the polygons' own velocities are those the last call started with), the
        contact's totals from the kernel's history; and its contact, ended at ``time`` (s)."""
        g = self._g
        done = []
        for i, k in closed:
            start = self._open.pop((int(ids[i]), k), None)
            if start is not None:  # None: began before the log (not expected)
                done.append((i, k, start))
        if not done:
            return
        hammers = [int(self._hammer_of[k]) for _, k, _ in done]
        vertices, first = g.polygons.vertices, g.polygons.start
        edges = [_first_edge(vertices, first, k) for _, k, _ in done]
        normals = [
            _turned(start.normal, start.edge, edge)
            for (_, _, start), edge in zip(done, edges, strict=True)
        ]
        rows = np.array([(i, k) for i, k, _ in done], dtype=np.int64)
        motion = _contact_motion(
            rows, np.array(normals), g.x, g.v, g.w, g.r, g.m, g.inertia, *hammers_now
        ).tolist()
        table = g.polygon_table
        others = self._others([(i, k) for i, k, _ in done])
        for (i, k, start), hammer, (vn, vt, _, _, energy), other, edge in zip(
            done, hammers, motion, others, edges, strict=True
        ):
            row = g.polygon_hist[i, k]
            peak = float(row[HIST_PEAK_FORCE])
            a, b = int(g.mat[i]), int(g.polygons.mat[k])
            pressure = (
                math.nan
                if table is None or table.law[a, b] == LINEAR
                else hertz_peak_pressure(peak, float(table.k_n[a, b]), float(g.r[i]))
            )
            self.impacts.append(
                Impact(
                    time=start.time,
                    granule=int(ids[i]),
                    hammer=hammer,
                    normal_velocity_before=start.normal_velocity,
                    normal_velocity_after=vn,
                    tangential_velocity_before=start.tangential_velocity,
                    tangential_velocity_after=vt,
                    normal_impulse=float(row[HIST_NORMAL_IMPULSE]),
                    point=start.point,
                    normal=start.normal,
                    granule_energy_gain=energy - start.granule_energy,
                    dissipated=float(row[HIST_DISSIPATED]),
                    hammer_energy_before=start.hammer.energy,
                    granule_velocity_before=start.granule_velocity,
                    hammer_swing_angle_before=start.hammer.swing_angle,
                    hammer_angular_velocity_before=start.hammer.angular_velocity,
                    peak_force=peak,
                    peak_pressure=pressure,
                    hammer_centre_before=start.hammer.centre,
                    granule_spin_before=start.granule_spin,
                    granule_spin_after=float(g.w[i]),
                    granule_velocity_after=(float(g.v[i, 0]), float(g.v[i, 1])),
                    held=start.held,
                    other_contacts=max(start.others, other),
                )
            )
            begun = start.time - self._dt
            self.contacts.append(
                Contact(
                    granule=int(ids[i]),
                    hammer=hammer,
                    start=begun,
                    end=time,
                    steps=round((time - begun) / self._dt),
                    normal=start.normal,
                    position_start=start.position,
                    velocity_start=start.granule_velocity,
                    spin_start=start.granule_spin,
                    position_end=(float(g.x[i, 0]), float(g.x[i, 1])),
                    velocity_end=(float(g.v[i, 0]), float(g.v[i, 1])),
                    spin_end=float(g.w[i]),
                    hammer_turn=_turn(start.edge, edge),
                    hammer_angular_velocity_start=start.hammer.angular_velocity,
                    hammer_angular_velocity_end=float(hammers_now[2][k]),
                    other_contacts=max(start.others, other),
                    held=start.held,
                )
            )


@numba.njit(cache=True)
def _other_contacts(pairs, hammer_of, movable, x, r, start, nbr, with_pairs, active, walls):
    """For each (granule row i, polygon k) of ``pairs``: i's contacts now (granules overlapping
    it in the neighbour list ``start``/``nbr`` if ``with_pairs``, walls it overlaps, polygons
    whose contact is ``active``) but those with the pieces of k's hammer h, plus, if
    ``movable[h]``, the other granules' active contacts with h's pieces."""
    n = x.shape[0]
    touching = np.zeros(n, np.int64)
    wanted = np.zeros(n, np.bool_)
    for q in range(pairs.shape[0]):
        wanted[pairs[q, 0]] = True
    if with_pairs and start.shape[0] == n + 1:
        for i in range(n):
            for p in range(start[i], start[i + 1]):
                j = nbr[p]
                if (wanted[i] or wanted[j]) and math.hypot(
                    x[i, 0] - x[j, 0], x[i, 1] - x[j, 1]
                ) < r[i] + r[j]:
                    touching[i] += 1
                    touching[j] += 1
    out = np.zeros(pairs.shape[0], np.int64)
    for q in range(pairs.shape[0]):
        i, h = pairs[q, 0], hammer_of[pairs[q, 1]]
        count = touching[i]
        for s in range(walls.shape[0]):
            count += wall_overlap(x[i, 0], x[i, 1], r[i], walls[s]) > 0.0
        for k in range(active.shape[1]):
            if active[i, k] != 0.0 and hammer_of[k] != h:
                count += 1
            if movable[h] and hammer_of[k] == h:
                for j in range(n):
                    if j != i and active[j, k] != 0.0:
                        count += 1
        out[q] = count
    return out


@numba.njit(cache=True, fastmath=FASTMATH)
def _start_normals(rows, x_before, vertices_before, x, vertices, start, solid, corner):
    """The outward normal of each contact (granule rows[e, 0], polygon rows[e, 1]) at its
    start, (n, 2): from the closest feature of the polygon to the granule's centre before the
    kernel call, or, where that centre faced no feature of this piece (it faced another
    piece's), after it (``closest_feature``, compiled with its own flags)."""
    out = np.empty((rows.shape[0], 2))
    for e in range(rows.shape[0]):
        i, k = rows[e, 0], rows[e, 1]
        d, nx, ny = closest_feature(
            x_before[i, 0], x_before[i, 1], vertices_before, start, solid, corner, k
        )
        if not math.isfinite(d):
            _, nx, ny = closest_feature(x[i, 0], x[i, 1], vertices, start, solid, corner, k)
        out[e, 0] = nx
        out[e, 1] = ny
    return out


@numba.njit(cache=True)
def _contact_motion(rows, normals, x, v, w, r, m, inertia, com, velocity, omega):
    """Per event e, granule i = rows[e, 0] on polygon k = rows[e, 1] with the outward normal
    n = normals[e]: the normal and tangential velocity (m/s) of the granule's contact point
    p = x_i − r_i n relative to the polygon's material point there (its centre of mass com[k],
    velocity and ω; t = n turned +90°), p (m), and the granule's kinetic energy ½m|v|² + ½Iw²
    (J), as rows (vn, vt, p_x, p_y, energy). Each operation as the formula is written, one at
    a time (no fast-math)."""
    out = np.empty((rows.shape[0], 5))
    for e in range(rows.shape[0]):
        i, k = rows[e, 0], rows[e, 1]
        nx, ny = normals[e, 0], normals[e, 1]
        px = x[i, 0] - r[i] * nx
        py = x[i, 1] - r[i] * ny
        tx, ty = -ny, nx
        rel_x = v[i, 0] - w[i] * r[i] * tx - (velocity[k, 0] - omega[k] * (py - com[k, 1]))
        rel_y = v[i, 1] - w[i] * r[i] * ty - (velocity[k, 1] + omega[k] * (px - com[k, 0]))
        out[e, 0] = rel_x * nx + rel_y * ny
        out[e, 1] = rel_x * tx + rel_y * ty
        out[e, 2] = px
        out[e, 3] = py
        speed2 = v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1]
        out[e, 4] = 0.5 * m[i] * speed2 + 0.5 * inertia[i] * w[i] * w[i]
    return out


@numba.njit(cache=True)
def _contact_changes(
    hist: np.ndarray,
    active: np.ndarray,
    is_hammer: np.ndarray,
    candidates: np.ndarray,
    out: np.ndarray,
) -> int:
    """Compare each (granule, polygon) contact flag of the kernel's polygon history with
    ``active`` (hammer polygons only) and bring ``active`` up to date; the changes go to the
    rows of ``out`` as (granule row, polygon, 1 opened / 0 closed), in row order. Returns their
    number.

    Only the rows that can have changed in the kernel's last call are read: those with an
    entry in its candidate list (``candidates``: ``SoftGranules.polygon_candidates``) or an
    open contact in ``active``. A pair in contact at the call's end was in the list of its last
    step (the list keeps every pair in contact), so a pair of any other row was in contact at
    neither end. With no list kept (another length) every row is read. The history is read
    strided, (n, n_poly, columns) doubles: reading every row cost most of a look."""
    count = 0
    listed = candidates.shape[0] == hist.shape[0] + 1
    for i in range(hist.shape[0]):
        if listed and candidates[i + 1] == candidates[i] and not active[i].any():
            continue
        for k in range(hist.shape[1]):
            now = is_hammer[k] and hist[i, k, HIST_ACTIVE] != 0.0
            if now != active[i, k]:
                out[count, 0] = i
                out[count, 1] = k
                out[count, 2] = 1 if now else 0
                count += 1
                active[i, k] = now
    return count
