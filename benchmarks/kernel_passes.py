"""Where a soft kernel step's time goes, pass by pass (issue 14): each pass of
``perga.contact.soft.kernel.advance`` timed alone inside a compiled loop on a live state, so
that numba's dispatch (about 4 µs a call for the 52 arrays ``advance`` takes) is not counted.

States (one thread):

* ``chamber``: the hammer chamber of ``dem_peers.py`` (3,000 granules, six welded plate
  hammers), after 100 machine steps;
* ``separator``: ``benchmarks/cases/soft-separator-1000.toml`` at t = 5 ms (``--at``);
* ``bed``: the settled 10,000-granule bed of ``beds.py``, after 20 steps.

Passes, ns a granule a step unless said:

* ``pairs``: the pair pass (``_pair_forces_serial``);
* ``granules``: the per-granule pass (``_integrate_serial``) with the state's polygon
  candidates and its flagged granules (``mark_special``), and ``granules, no candidates``
  without the candidates;
* ``polygon contact``: ``polygon_contact`` for each candidate entry, ns an entry;
* ``build``: the neighbour-list build (``neighbours.build``), ns a granule a build.

Each block starts from a copy of the state and calls the pass about a million granule-steps'
worth of times (the per-granule pass with the pair forces zeroed: ``runner``); figures are
medians and ranges over blocks. Digests are not printed: these are timings
of parts, and ``soft_kernel.py`` checks results.

    python benchmarks/kernel_passes.py                     # the three states, ~1 min
    python benchmarks/kernel_passes.py --states chamber --blocks 7
    python benchmarks/kernel_passes.py --states separator --at 0.04   # later in the run
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import beds
import numpy as np
from numba import njit

from perga.case import load_case
from perga.contact.soft import SoftGranules
from perga.contact.soft import kernel as k
from perga.contact.soft.laws import LINEAR, P_DAMPT, P_HERTZ, P_MU, P_MUR
from perga.contact.soft.neighbours import build
from perga.contact.soft.polygon_forces import Candidates, polygon_contact
from perga.contact.soft.polygon_set import PolygonArrays, TableArrays
from perga.engine import Simulation
from perga.geometry.disc_polygon import FASTMATH, bounding_radii
from perga.model.compile import compile_case

ROOT = Path(__file__).resolve().parents[1]


def chamber() -> SoftGranules:
    """The hammer chamber of ``dem_peers.py`` after 100 machine steps."""
    import dem_peers
    import engine_vs_pymunk

    positions = np.array(engine_vs_pymunk.granule_positions(3000))
    spec = dem_peers.mill_case(positions, Path(tempfile.mkdtemp()))
    sim = Simulation(spec, record_impacts=False, track_energy=False)
    sim.contacts.granules.set_threads(1)
    for _ in range(100):
        sim.step()
    return sim.contacts.granules


def separator(at: float = 0.005) -> SoftGranules:
    """``benchmarks/cases/soft-separator-1000.toml`` at t = at, s (5 ms unless given)."""
    case = load_case(
        ROOT / "benchmarks/cases/soft-separator-1000.toml", overrides=["solver.threads=1"]
    )
    sim = Simulation(compile_case(case), record_impacts=False, track_energy=False)
    while sim.time < at:
        sim.step()
    return sim.contacts.granules


def bed() -> SoftGranules:
    """The settled 10,000-granule bed after 20 steps."""
    saved = beds.load(10_000)
    g = beds.soft_bed(saved.x, saved.width, threads=1)
    g.step(20)
    return g


STATES: dict[str, Callable[[], SoftGranules]] = {
    "chamber": chamber,
    "separator": separator,
    "bed": bed,
}


@njit(parallel=True, fastmath=FASTMATH, error_model="numpy")
def _pairs(reps, x, v, w, a_prev, r, m, inertia, mat, params, nbrs, dt, reach, tangential,
           rolling, linear, acc, lost, flags):  # fmt: skip
    """The pair pass, reps times."""
    start, nbr, hist = nbrs
    for _ in range(reps):
        k._pair_forces_serial(
            x, v, w, a_prev, r, m, inertia, mat, params, start, nbr, hist, dt, reach, tangential,
            rolling, linear, acc, lost, flags,
        )  # fmt: skip


@njit
def _granules(reps, granules, props, bonds, params, walls, poly, table, phist, cand, settings,
              work, x_ref, reach, wall_gap, covered):  # fmt: skip
    """The per-granule pass, reps times, with the granules flagged as ``advance`` would."""
    n = granules.x.shape[0]
    rho = bounding_radii(poly.vertices, poly.start, poly.com)
    flags = np.empty(n, np.int8)
    order = np.empty(n, np.int64)
    count = k.mark_special(wall_gap, covered, cand.start, bonds.held, flags, order)
    chunk = np.zeros((work.acc.shape[0], 6))
    for _ in range(reps):
        k._integrate_serial(
            granules, props, bonds, params, walls, poly, table, phist, rho, cand, settings, work,
            x_ref, chunk, 0, reach, (wall_gap, flags, order[:count], order[:0]), reach,
        )  # fmt: skip


@njit(parallel=True, fastmath=FASTMATH, error_model="numpy")
def _contacts(reps, owner, polygon, x, v, w, r, m, mat, poly, table, dt, phist):
    """``polygon_contact`` for every candidate entry (granule owner[e], polygon[e]), reps times."""
    rho = bounding_radii(poly.vertices, poly.start, poly.com)
    total = 0.0
    for _ in range(reps):
        for e in range(owner.shape[0]):
            total += polygon_contact(
                owner[e], polygon[e], x, v, w, r, m, mat, poly, table, rho, dt, phist
            )[1]
    return total


@njit
def _build(reps, x, r, skin, start, nbr, hist):
    """The neighbour-list build, reps times."""
    for _ in range(reps):
        start, nbr, hist = build(x, r, skin, start, nbr, hist)


PASSES = ("pairs", "granules", "granules, no candidates", "build", "polygon contact")


def runner(g: SoftGranules, part: str) -> tuple[Callable[[int], object], int, int, str] | None:
    """(run(reps), reps a block, count, unit) of pass ``part`` on the state g (which it uses up),
    or None where the state has nothing for it; the time of a block over reps·count is the
    figure. The per-granule pass runs with the pair forces zeroed: the forces of the state,
    applied for the block's hundreds of steps, would fling touching granules apart."""
    settings, granules, props, bonds, params, walls, polys, nbrs, work = g._bundles(
        *g._poly, 5, 0.0, math.inf
    )
    x, v, w, a_prev = granules
    r, m, inertia, mat = props
    n, dt = g.n, g.dt
    steps = max(1, 1_000_000 // n)  # calls a block: about a million granule-steps
    u = v + 0.5 * dt * a_prev[:, :2]
    reach = dt * math.sqrt(float((u * u).sum(axis=1).max()))
    poly, table, phist = PolygonArrays(*polys[0]), TableArrays(*polys[1]), polys[2]
    cstart, cpoly = g._listed[0], g._listed[1]
    if cstart.shape[0] != n + 1:
        cstart = np.zeros(n + 1, np.int64)
    if part == "pairs":
        lost = np.zeros(work[0].shape[0])
        tangential = bool(np.any(params[..., P_MU] != 0.0) or np.any(params[..., P_DAMPT] != 0.0))
        rolling = bool(np.any(params[..., P_MUR] != 0.0))
        linear = bool(np.all(params[..., P_HERTZ] == LINEAR))
        return (
            lambda reps: _pairs(
                reps, x, v, w, a_prev, r, m, inertia, mat, params, nbrs[:3], dt, reach,
                tangential, rolling, linear, work[0], lost, np.zeros(n, np.int8),
            ),
            steps, n, "ns a granule a step",
        )  # fmt: skip
    if part == "build":
        return (
            lambda reps: _build(reps, x, r, g.skin, *nbrs[:3]),
            max(1, steps // 20), n, "ns a granule a build",
        )  # fmt: skip
    if part == "polygon contact":
        owner = np.repeat(np.arange(n), np.diff(cstart))
        if owner.size == 0:
            return None
        return (
            lambda reps: _contacts(reps, owner, cpoly, x, v, w, r, m, mat, poly, table, dt, phist),
            steps, owner.size, f"ns an entry ({owner.size} entries)",
        )  # fmt: skip
    work[0][...] = 0.0
    if part == "granules, no candidates":
        cstart, cpoly = np.zeros(n + 1, np.int64), np.zeros(0, np.int64)
    cand = Candidates(cstart, cpoly, np.zeros((cpoly.shape[0], 4)))
    wall_gap = np.empty(n)
    k.wall_gaps(g.x_ref, r, *walls, wall_gap)
    bundles = (
        k.Granules(*granules), k.GranuleProps(*props), k.Bonds(*bonds), params,
        k.Walls(*walls), poly, table, phist, cand, k.Settings(*settings), k.Work(*work), g.x_ref,
    )  # fmt: skip
    covered = reach + k.SPECIAL_MARGIN * g.skin
    return (
        lambda reps: _granules(reps, *bundles, reach, wall_gap, covered),
        steps, n, "ns a granule a step",
    )  # fmt: skip


def timings(state: SoftGranules, blocks: int) -> list[tuple[str, float, float, float, str]]:
    """(pass, median, low, high, unit) of each pass, every block from a copy of ``state``."""
    rows = []
    for part in PASSES:
        times = []
        unit = ""
        for block in range(blocks + 1):  # the first compiles and is not counted
            made = runner(copy.deepcopy(state), part)
            if made is None:
                break
            run, reps, count, unit = made
            t0 = time.perf_counter()
            run(reps)
            if block:
                times.append(1e9 * (time.perf_counter() - t0) / (reps * count))
        if times:
            rows.append((part, statistics.median(times), min(times), max(times), unit))
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--states", nargs="+", choices=list(STATES), default=list(STATES))
    p.add_argument("--blocks", type=int, default=5)
    p.add_argument("--at", type=float, default=0.005, help="the separator state's time, s")
    args = p.parse_args(argv)
    print(f"load {os.getloadavg()[0]:.2f}; {args.blocks} blocks; one thread")
    for name in args.states:
        g = separator(args.at) if name == "separator" else STATES[name]()
        entries = g.nbr.size / g.n
        print(f"\n{name}: {g.n} granules, {entries:.2f} list entries a granule")
        for part, median, low, high, unit in timings(g, args.blocks):
            print(f"  {part:24s} {median:8.2f} ({low:.2f}-{high:.2f}) {unit}")
    print(f"\nload {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
