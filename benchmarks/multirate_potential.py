"""Issue 14, item 5, measured before anything is built: in a soft separator, how many granules
could take one machine step instead of k granule steps because nothing can reach them within it.

At every ``--every``-th machine step of a run (one thread) the granules are classified: a granule
is *free* over the coming machine step T = k·dt when its gap to every other granule, to every
hammer polygon's bounding circle and to the round chamber wall exceeds the distance the two can
close in T, with a bound on speeds that covers a contact within T: each granule's own speed plus
v_bound = 2·(the fastest granule + the fastest polygon point) (a granule struck by a hammer leaves
it at no more than twice the hammer's speed plus its own), and held granules are never free.
The kernel's cost per machine step would then be about (active·k + free)/(n·k) of the uniform
step's (pairs and polygons included), which is the bound on the speed-up printed: the work of
one granule step is taken as the same for every granule, which overstates what a granule in free
flight costs today (it has no contacts) and so understates the gain.

``--local`` adds a per-neighbourhood bound beside the global one: only granules a hammer can
reach within T (gap to a polygon's bounding circle within what the two close at v_bound), and
those such a granule can reach in turn (closed over chains), take v_bound; every other granule
can only be sped up by granules as slow as itself, and takes twice the fastest of them.

    python benchmarks/multirate_potential.py                       # both soft separators
    python benchmarks/multirate_potential.py --cases soft-separator --every 50
    python benchmarks/multirate_potential.py --local --factors 1 10 100

Also printed: how many granules touch something (a granule, the wall or a hammer) at the
sampled steps: what a contact must be resolved for, against the granules that are stepped.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from perga.case import load_case
from perga.contact.soft.granules import overlapping_pairs, wall_overlaps
from perga.contact.soft.polygon_set import HIST_ACTIVE
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "soft-separator": (ROOT / "cases/soft-separator.toml", 0.5),
    "soft-separator-1000": (ROOT / "benchmarks/cases/soft-separator-1000.toml", 0.05),
}


def free_share(sim: Simulation, factor: int = 1, local: bool = False) -> float:
    """The share of granules free over the coming ``factor`` machine steps (module doc; with
    ``local`` the per-neighbourhood speed bound)."""
    g = sim.contacts.granules
    p = sim.contacts.polygons.polygons
    x, v, r = g.x, g.v, g.r
    n = len(r)
    if n == 0:
        return 1.0
    span = sim.dt * factor
    speed = np.hypot(v[:, 0], v[:, 1])
    centres = p.com
    rho = np.array(
        [np.max(np.hypot(*(p.vertices[a:b] - p.com[k]).T)) for k, (a, b) in
         enumerate(zip(p.start[:-1], p.start[1:], strict=True))]
    )  # fmt: skip
    poly_speed = np.hypot(p.velocity[:, 0], p.velocity[:, 1]) + np.abs(p.omega) * rho
    v_bound = 2.0 * (speed.max() + (poly_speed.max() if len(rho) else 0.0))
    fall = np.hypot(*g.gravity) * span**2
    tree = cKDTree(x)
    bound = np.full(n, v_bound)
    if local:
        bound = _local_bounds(x, r, speed, tree, centres, rho, poly_speed, v_bound, span, fall)
    reach = (speed + bound) * span + fall
    free = g.held == 0
    for i, j in tree.query_pairs(2.0 * r.max() + reach.max(), output_type="ndarray"):
        gap = np.hypot(*(x[i] - x[j])) - r[i] - r[j]
        if gap <= reach[i] + reach[j]:
            free[i] = free[j] = False
    for k in range(len(rho)):
        gap = np.hypot(*(x - centres[k]).T) - rho[k] - r
        free &= gap > reach + poly_speed[k] * span
    chamber = sim.spec.chamber
    if chamber is not None:
        free &= chamber.radius - np.hypot(x[:, 0], x[:, 1]) - r > reach
    return float(free.mean())


def touching(sim: Simulation) -> int:
    """The granules that overlap another granule or a wall, or act on a hammer polygon."""
    g = sim.contacts.granules
    i, j, _, _ = overlapping_pairs(g.x, g.r, g.start, g.nbr, g.hist, False)
    touched = np.zeros(g.n, dtype=bool)
    touched[i] = touched[j] = True
    touched |= (wall_overlaps(g.x, g.r, g.walls) > 0.0).any(axis=1)
    touched |= (g.polygon_hist[:, :, HIST_ACTIVE] != 0.0).any(axis=1)
    return int(touched.sum())


def _local_bounds(x, r, speed, tree, centres, rho, poly_speed, v_bound, span, fall):
    """Per granule, the speed it may gain within ``span`` (s): v_bound for the granules a hammer
    (bounding circle ``centres``, ``rho``, point speed ``poly_speed``) can strike, and for every
    granule a struck one can reach in turn; twice the fastest of the others for the rest."""
    hot = np.zeros(len(r), dtype=bool)
    for k in range(len(rho)):
        gap = np.hypot(*(x - centres[k]).T) - rho[k] - r
        hot |= gap <= (speed + v_bound + poly_speed[k]) * span + fall
    reach = (speed + v_bound) * span + fall
    radius = 2.0 * r.max() + 2.0 * reach.max()
    frontier = np.flatnonzero(hot)
    while frontier.size:
        added = []
        for i, near in zip(frontier, tree.query_ball_point(x[frontier], radius), strict=True):
            for j in near:
                if not hot[j] and np.hypot(*(x[i] - x[j])) - r[i] - r[j] <= reach[i] + reach[j]:
                    hot[j] = True
                    added.append(j)
        frontier = np.array(added, dtype=int)
    cold = 2.0 * speed[~hot].max() if (~hot).any() else 0.0
    return np.where(hot, v_bound, cold)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=sorted(CASES), default=list(CASES))
    parser.add_argument("--every", type=int, default=100, help="classify every n-th step")
    parser.add_argument(
        "--factors", type=int, nargs="+", default=[1, 10],
        help="free over this many machine steps (a longer free step)",
    )  # fmt: skip
    parser.add_argument(
        "--local", action="store_true", help="also the per-neighbourhood speed bound"
    )
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    for name in args.cases:
        path, duration = CASES[name]
        case = load_case(path, overrides=[f"solver.duration={duration}", "solver.threads=1"])
        sim = Simulation(compile_case(case), record_impacts=False, track_energy=False)
        k = sim.contacts.substeps
        bounds = (False, True) if args.local else (False,)
        shares: dict[tuple[bool, int], list[float]] = {
            (b, f): [] for b in bounds for f in args.factors
        }
        steps = round(duration / sim.dt)
        touched = []
        for step in range(steps):
            if step % args.every == 0:
                touched.append(touching(sim))
                for b, f in shares:
                    shares[b, f].append(free_share(sim, f, b))
            sim.step()
        samples = len(shares[False, args.factors[0]])
        print(f"{name}: {len(sim.contacts.granules.r)} granules, k = {k} granule steps per "
              f"machine step, {samples} samples over {duration} s")  # fmt: skip
        print(f"  granules touching something: mean {np.mean(touched):.1f}, most {max(touched)}")
        for (b, f), values in shares.items():
            s_ = np.array(values)
            cost = (1.0 - s_) + s_ / (k * f)
            print(
                f"  {'local' if b else 'global'} bound, free over {f} machine step(s) "
                f"({k * f} granule steps): share mean {s_.mean():.3f} (min {s_.min():.3f}, "
                f"max {s_.max():.3f}); kernel cost bound {cost.mean():.3f} of the uniform "
                f"step, speed-up <= {1 / cost.mean():.2f}"
            )
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
