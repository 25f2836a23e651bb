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
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np

from perga.contact.soft import SoftGranules
from perga.contact.soft.kernel import COUNT_CONTACT_CHANGES
from perga.contact.soft.polygon_set import (
    HIST_ACTIVE,
    HIST_DISSIPATED,
    HIST_NORMAL_IMPULSE,
    HIST_PEAK_FORCE,
    LINEAR,
)
from perga.geometry.disc_polygon import closest_feature
from perga.model.records import HammerState, Impact

if TYPE_CHECKING:
    from perga.engine.machine import MachineState


@dataclass(frozen=True)
class _Start:
    time: float
    normal: tuple[float, float]
    hammer_angle: float
    normal_velocity: float
    tangential_velocity: float
    point: tuple[float, float]
    granule_energy: float
    granule_velocity: tuple[float, float]
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


def _rotate(n: tuple[float, float], angle: float) -> tuple[float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return (c * n[0] - s * n[1], s * n[0] + c * n[1])


class SoftImpactLog:
    """Impacts of ``granules`` on the hammers, polygon k of ``granules.polygons`` being a piece
    of hammer ``hammer_of[k]`` (−1: not a hammer; a contact with each piece is an impact of
    its own); call :meth:`before` before and :meth:`after` after every kernel call, and
    :meth:`rows_changed` when granules are added or removed. ``hammer_state(h)`` gives hammer
    h's :class:`~perga.model.records.HammerState` now, ``ids()`` the id of each granule row."""

    def __init__(
        self,
        granules: SoftGranules,
        hammer_of: np.ndarray,
        hammer_state: Callable[[int], HammerState],
        ids: Callable[[], np.ndarray],
    ) -> None:
        self.impacts: list[Impact] = []
        self._g = granules
        self._ids = ids
        self._hammer_of = hammer_of
        self._hammer_state = hammer_state
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

    def _energy(self, i: int, v: np.ndarray, w: float) -> float:
        g = self._g
        return float(0.5 * g.m[i] * (v @ v) + 0.5 * g.inertia[i] * w * w)

    def _relative(
        self, i: int, k: int, x, v, w, n, com
    ) -> tuple[float, float, tuple[float, float]]:
        """Normal and tangential velocity of granule i's contact point relative to polygon k's
        material point there (polygon centre of mass ``com``), and the point (m/s, m)."""
        p = self._g.polygons
        r = self._g.r[i]
        point = (x[0] - r * n[0], x[1] - r * n[1])
        t = (-n[1], n[0])
        rel_x = v[0] - w * r * t[0] - (p.velocity[k, 0] - p.omega[k] * (point[1] - com[1]))
        rel_y = v[1] - w * r * t[1] - (p.velocity[k, 1] + p.omega[k] * (point[0] - com[0]))
        vn = float(rel_x * n[0] + rel_y * n[1])
        return vn, float(rel_x * t[0] + rel_y * t[1]), (float(point[0]), float(point[1]))

    def before(self) -> None:
        """Keep the granules' and polygons' state before a kernel call (starts need it)."""
        g, p = self._g, self._g.polygons
        if self._x.shape != g.x.shape:
            self._x, self._v, self._w = np.empty_like(g.x), np.empty_like(g.v), np.empty_like(g.w)
        _keep(g.x, g.v, g.w, p.vertices, p.com, self._x, self._v, self._w, self._vertices,
              self._com)  # fmt: skip

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
        only when the kernel counted a change since the last look (``SoftGranules.counts``)."""
        g = self._g
        seen = int(g.counts[COUNT_CONTACT_CHANGES])
        if seen == self._seen:
            return
        angles = machine.angle[hammer_rows]  # each hammer's body angle now, rad
        self._seen = seen
        hist = g.polygon_hist
        if self._changes.shape[0] < self._active.size:
            self._changes = np.empty((self._active.size, 3), dtype=np.int64)
        count = _contact_changes(
            hist, self._active, self._is_hammer, g.polygon_candidates, self._changes
        )
        if count == 0:
            return
        ids = self._ids()
        changes = self._changes[:count]
        for i, k in changes[changes[:, 2] == 0, :2].tolist():
            self._close(i, int(ids[i]), k, hist[i, k], angles)
        for i, k in changes[changes[:, 2] == 1, :2].tolist():
            angle = angles[self._hammer_of[k]]
            self._open[(int(ids[i]), k)] = self._start(i, k, time, angle)

    def _start(self, i: int, k: int, time: float, angle: float) -> _Start:
        p = self._g.polygons
        d, nx, ny = closest_feature(
            self._x[i, 0], self._x[i, 1], self._vertices, p.start, p.solid, p.corner, k
        )
        if not math.isfinite(d):  # before the call the centre faced another piece's feature
            _, nx, ny = closest_feature(self._g.x[i, 0], self._g.x[i, 1], *p.outline(), k)
        n = (float(nx), float(ny))
        vn, vt, point = self._relative(
            i, k, self._x[i], self._v[i], float(self._w[i]), n, self._com[k]
        )
        return _Start(
            time=time,
            normal=n,
            hammer_angle=angle,
            normal_velocity=vn,
            tangential_velocity=vt,
            point=point,
            granule_energy=self._energy(i, self._v[i], float(self._w[i])),
            granule_velocity=(float(self._v[i, 0]), float(self._v[i, 1])),
            hammer=self._hammer_state(int(self._hammer_of[k])),
        )

    def _close(self, i: int, id_: int, k: int, row: np.ndarray, angles: np.ndarray) -> None:
        start = self._open.pop((id_, k), None)
        if start is None:  # began before the log (not expected: it starts with the run)
            return
        g = self._g
        hammer = int(self._hammer_of[k])
        n = _rotate(start.normal, float(angles[hammer]) - start.hammer_angle)
        vn, vt, _ = self._relative(i, k, g.x[i], g.v[i], float(g.w[i]), n, g.polygons.com[k])
        peak = float(row[HIST_PEAK_FORCE])
        a, b = int(g.mat[i]), int(g.polygons.mat[k])
        table = g.polygon_table
        pressure = (
            math.nan
            if table is None or table.law[a, b] == LINEAR
            else hertz_peak_pressure(peak, float(table.k_n[a, b]), float(g.r[i]))
        )
        self.impacts.append(
            Impact(
                time=start.time,
                granule=id_,
                hammer=hammer,
                normal_velocity_before=start.normal_velocity,
                normal_velocity_after=vn,
                tangential_velocity_before=start.tangential_velocity,
                tangential_velocity_after=vt,
                normal_impulse=float(row[HIST_NORMAL_IMPULSE]),
                point=start.point,
                normal=start.normal,
                granule_energy_gain=self._energy(i, g.v[i], float(g.w[i])) - start.granule_energy,
                dissipated=float(row[HIST_DISSIPATED]),
                hammer_energy_before=start.hammer.energy,
                granule_velocity_before=start.granule_velocity,
                hammer_swing_angle_before=start.hammer.swing_angle,
                hammer_angular_velocity_before=start.hammer.angular_velocity,
                peak_force=peak,
                peak_pressure=pressure,
            )
        )


@numba.njit(cache=True)
def _keep(x, v, w, vertices, com, x_out, v_out, w_out, vertices_out, com_out):
    """Copy the granules' and polygons' state into the log's arrays of the same shapes."""
    _copy(x, x_out)
    _copy(v, v_out)
    _copy(w, w_out)
    _copy(vertices, vertices_out)
    _copy(com, com_out)


@numba.njit(cache=True)
def _copy(source, target):
    """Copy the C-contiguous array ``source`` into ``target`` of its shape, as one flat loop
    (numba's ``target[:] = source`` of a 2-D array indexes every element: slower,
    docs/performance.md)."""
    a = source.reshape(-1)
    b = target.reshape(-1)
    for k in range(a.size):
        b[k] = a[k]


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
