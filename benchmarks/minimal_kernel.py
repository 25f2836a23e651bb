"""A minimal numba DEM kernel for the dense beds of ``beds.py``: the floor line of
``dem_peers.py`` (what the same physics costs with nothing else in the loop).

One thread, 2-D discs, all of one radius r and mass m (the bed's: scalars, no material table),
floor y = 0 and side walls x = 0 and x = width (plane walls), gravity. Law of ``beds.py``
(LAMMPS gran/hooke/history with ``limit_damping``, no tangential damping):

* normal, while δ > 0: F_n = max(k_n δ + η_n δ̇, 0), η_n = 2ζ√(k_n m_eff), ζ for e = 0.7 with
  the force clamped at zero (``damping_ratio(E, "force")``); m_eff = m/2 for a pair, m at a wall;
* tangential: a spring with history, ξ += v_t dt, F_t = −k_t ξ, k_t = 2/7 k_n, capped at
  μ F_n (μ = 0.5) with ξ then set to −F_t/k_t; ξ is reset when the contact opens. Lever arms
  r − δ/2 for a pair (as perga), r at a wall.

Integrator: perga's (``perga.contact.soft.kernel``): symplectic Euler, forces from x and the
velocities extrapolated to the force time, u = v + ½ dt a_prev, then v += a dt, x += v dt.
The plain dashpot above differs from perga's at first touch only (perga integrates it over the
part of the step the discs overlap and starts a contact half a step early): same law, O(dt).

Neighbours: a Verlet half list (CSR: the j > i of i are ``nbr[start[i]:start[i + 1]]``, one
ξ per entry) built on a cell grid of cells 2r + skin (our own serial build, ``build_list``, not
``perga.contact.soft.neighbours.build``, which is a parallel loop), the ξ of surviving pairs
carried over, rebuilt before a step when any granule has moved more than skin/2 since the
last build. dt = t_c/50 and skin 0.4 r: ``beds.time_step()``, ``beds.SKIN``.

    python benchmarks/minimal_kernel.py 1000 --steps 3000   # one run of the cached bed
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass

import beds
import numpy as np
from numba import njit

from perga.analytic.contact import damping_ratio
from perga.geometry.disc_polygon import FASTMATH  # perga's compile flags: a like-for-like floor

ZETA = damping_ratio(beds.E, beds.END)


@njit(cache=True, error_model="numpy")
def build_list(x, reach, old_start, old_nbr, old_hist):
    """Half list (start, nbr, hist) of the pairs closer than reach (m) at positions x (n, 2),
    on a grid of cells ≥ reach; the history of pairs of the old list is carried over."""
    n = x.shape[0]
    x0, y0 = x[:, 0].min(), x[:, 1].min()
    size = reach
    while ((x[:, 0].max() - x0) / size + 1.0) * ((x[:, 1].max() - y0) / size + 1.0) > 4 * n + 16:
        size *= 2.0  # a granule flung far away widens the cells instead of the grid
    ncx = int((x[:, 0].max() - x0) / size) + 1
    ncy = int((x[:, 1].max() - y0) / size) + 1
    cell = np.empty(n, np.int64)
    first = np.zeros(ncx * ncy + 1, np.int64)
    for i in range(n):
        cell[i] = int((x[i, 1] - y0) / size) * ncx + int((x[i, 0] - x0) / size)
        first[cell[i] + 1] += 1
    for c in range(ncx * ncy):
        first[c + 1] += first[c]
    order = np.empty(n, np.int64)
    fill = first[:-1].copy()
    for i in range(n):
        order[fill[cell[i]]] = i
        fill[cell[i]] += 1
    start = np.zeros(n + 1, np.int64)
    nbr = np.empty(8 * n, np.int64)
    k = 0
    for i in range(n):
        cx, cy = cell[i] % ncx, cell[i] // ncx
        for gy in range(max(cy - 1, 0), min(cy + 2, ncy)):
            for s in range(first[gy * ncx + max(cx - 1, 0)], first[gy * ncx + min(cx + 2, ncx)]):
                j = order[s]
                dx, dy = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1]
                if j > i and dx * dx + dy * dy < reach * reach:
                    if k == nbr.shape[0]:
                        nbr = np.concatenate((nbr, np.empty(k, np.int64)))
                    nbr[k] = j
                    k += 1
        start[i + 1] = k
    nbr = nbr[:k].copy()
    hist = np.zeros(k)
    if old_start.shape[0] == n + 1:
        for i in range(n):
            for q in range(start[i], start[i + 1]):
                for o in range(old_start[i], old_start[i + 1]):
                    if old_nbr[o] == nbr[q]:
                        hist[q] = old_hist[o]
                        break
    return start, nbr, hist


@njit(cache=True, fastmath=FASTMATH, error_model="numpy")
def advance(x, v, w, a, x_ref, start, nbr, hist, wall_hist, p, steps):
    """steps steps of the bed, in place (module doc); returns the list (start, nbr, hist) and
    the number of rebuilds.

    x, v (n, 2): m, m/s; w (n,): rad/s; a (n, 3): the last step's accelerations (a_x, a_y, α),
    m/s², rad/s²; x_ref (n, 2): positions at the list's build, m; wall_hist (n, 3): ξ at the
    floor, left and right walls, m; p = (r, m, k_n, k_t, η_pair, η_wall, μ, dt, g, width, skin)
    in SI (g > 0 pulls towards −y)."""
    r, m, kn, kt, eta, eta_w, mu, dt, g, width, skin = p
    n = x.shape[0]
    h = 0.5 * dt
    inertia = 0.5 * m * r * r
    f = np.zeros((n, 3))
    walls = ((0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (-1.0, 0.0, width))  # gap = x·(nx, ny) + c
    rebuilds = 0
    moved = 0.0
    for i in range(n):
        moved = max(moved, (x[i, 0] - x_ref[i, 0]) ** 2 + (x[i, 1] - x_ref[i, 1]) ** 2)
    for _ in range(steps):
        if moved > 0.25 * skin * skin:  # largest displacement² since the build > (skin/2)²
            start, nbr, hist = build_list(x, 2.0 * r + skin, start, nbr, hist)
            x_ref[:, :] = x
            rebuilds += 1
        for i in range(n):
            for k in range(start[i], start[i + 1]):
                j = nbr[k]
                dx, dy = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1]
                d2 = dx * dx + dy * dy
                if d2 >= 4.0 * r * r:
                    hist[k] = 0.0
                    continue
                d = math.sqrt(d2)
                nx, ny = dx / d, dy / d
                delta = 2.0 * r - d
                ux = v[i, 0] - v[j, 0] + h * (a[i, 0] - a[j, 0])
                uy = v[i, 1] - v[j, 1] + h * (a[i, 1] - a[j, 1])
                arm = r - 0.5 * delta
                vt = -ux * ny + uy * nx - arm * (w[i] + w[j] + h * (a[i, 2] + a[j, 2]))
                fn = max(kn * delta - eta * (ux * nx + uy * ny), 0.0)
                xi = hist[k] + vt * dt
                ft = -kt * xi
                if abs(ft) > mu * fn:
                    ft = math.copysign(mu * fn, ft)
                    xi = -ft / kt
                hist[k] = xi
                fx, fy = fn * nx - ft * ny, fn * ny + ft * nx
                f[i, 0] += fx
                f[i, 1] += fy
                f[i, 2] -= arm * ft
                f[j, 0] -= fx
                f[j, 1] -= fy
                f[j, 2] -= arm * ft
        moved = 0.0
        for i in range(n):
            ux, uy = v[i, 0] + h * a[i, 0], v[i, 1] + h * a[i, 1]
            wi = w[i] + h * a[i, 2]
            for s in range(3):
                nx, ny, c = walls[s]
                delta = r - (x[i, 0] * nx + x[i, 1] * ny + c)
                if delta <= 0.0:
                    wall_hist[i, s] = 0.0
                    continue
                fn = max(kn * delta - eta_w * (ux * nx + uy * ny), 0.0)
                xi = wall_hist[i, s] + (-ux * ny + uy * nx - r * wi) * dt
                ft = -kt * xi
                if abs(ft) > mu * fn:
                    ft = math.copysign(mu * fn, ft)
                    xi = -ft / kt
                wall_hist[i, s] = xi
                f[i, 0] += fn * nx - ft * ny
                f[i, 1] += fn * ny + ft * nx
                f[i, 2] -= r * ft
            a[i, 0] = f[i, 0] / m
            a[i, 1] = f[i, 1] / m - g
            a[i, 2] = f[i, 2] / inertia
            f[i, 0] = f[i, 1] = f[i, 2] = 0.0
            v[i, 0] += dt * a[i, 0]
            v[i, 1] += dt * a[i, 1]
            w[i] += dt * a[i, 2]
            x[i, 0] += dt * v[i, 0]
            x[i, 1] += dt * v[i, 1]
            ex, ey = x[i, 0] - x_ref[i, 0], x[i, 1] - x_ref[i, 1]
            moved = max(moved, ex * ex + ey * ey)
    return start, nbr, hist, rebuilds


def parameters(width: float) -> tuple[float, ...]:
    """The ``advance`` parameter tuple of ``beds.py``'s law in a box of this width (m)."""
    r, m, kn = beds.RADIUS, beds.MASS, beds.K_N
    return (
        r, m, kn, beds.KT_RATIO * kn, 2.0 * ZETA * math.sqrt(kn * m / 2.0),
        2.0 * ZETA * math.sqrt(kn * m), beds.FRICTION, beds.time_step(), beds.GRAVITY, width,
        beds.SKIN,
    )  # fmt: skip


@dataclass
class MinimalBed:
    """The state of a bed in the minimal kernel: arrays of ``advance``, its list, rebuilds."""

    x: np.ndarray
    v: np.ndarray
    w: np.ndarray
    a: np.ndarray
    x_ref: np.ndarray
    start: np.ndarray
    nbr: np.ndarray
    hist: np.ndarray
    wall_hist: np.ndarray
    p: tuple[float, ...]
    rebuilds: int = 0

    @classmethod
    def of(cls, x: np.ndarray, width: float, v: np.ndarray | None = None) -> MinimalBed:
        """A bed at positions x (n, 2), m, velocities v (n, 2), m/s (rest if None), in a box of
        this width, m, at rest otherwise, springs empty; its first list built."""
        n = x.shape[0]
        bed = cls(
            np.array(x, float), np.zeros((n, 2)) if v is None else np.array(v, float),
            np.zeros(n), np.zeros((n, 3)), np.array(x, float), np.zeros(1, np.int64),
            np.zeros(0, np.int64), np.zeros(0), np.zeros((n, 3)), parameters(width),
        )  # fmt: skip
        bed.start, bed.nbr, bed.hist = bed.build()
        return bed

    @property
    def dt(self) -> float:
        return self.p[7]

    def build(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A list of the current positions (carrying the history over)."""
        return build_list(self.x, 2.0 * self.p[0] + self.p[10], self.start, self.nbr, self.hist)

    def step(self, steps: int) -> None:
        self.start, self.nbr, self.hist, k = advance(
            self.x, self.v, self.w, self.a, self.x_ref, self.start, self.nbr, self.hist,
            self.wall_hist, self.p, int(steps),
        )  # fmt: skip
        self.rebuilds += k

    def touching(self) -> int:
        """Granule pairs overlapping now (δ > 0)."""
        i = np.repeat(np.arange(self.x.shape[0]), np.diff(self.start))
        d = np.linalg.norm(self.x[i] - self.x[self.nbr], axis=1)
        return int(np.count_nonzero(d < 2.0 * self.p[0]))


def run(x: np.ndarray, width: float, steps: int, v: np.ndarray | None = None):
    """steps steps of the bed at x (``beds.load(n).x``, m) in a box of this width (m), from
    velocities v (m/s; rest if None): (x, v, w, touching pairs) at the end."""
    bed = MinimalBed.of(x, width, v)
    bed.step(steps)
    return bed.x, bed.v, bed.w, bed.touching()


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("n", type=int, help="bed granules (beds.py)")
    p.add_argument("--steps", type=int, default=3000)
    args = p.parse_args()
    bed = beds.load(args.n)
    MinimalBed.of(bed.x, bed.width).step(2)  # compiles or loads, untimed
    m = MinimalBed.of(bed.x, bed.width)
    t0 = time.perf_counter()
    m.step(args.steps)
    seconds = time.perf_counter() - t0
    print(
        f"n = {args.n}: {args.steps} steps in {seconds:.2f} s, "
        f"{seconds / (args.n * args.steps) * 1e9:.1f} ns a particle-step, {m.rebuilds} rebuilds, "
        f"{2 * m.touching() / args.n:.2f} touching pairs per granule"
    )


if __name__ == "__main__":
    main()
