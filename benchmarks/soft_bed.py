"""Soft-granule kernel speed on a dense settled bed: particle-steps per second, 1 and 2 threads.

The case (design §8's inputs): 2-D discs of radius 2 mm, mass of a sphere of density 1400 kg/m³,
linear spring-dashpot k_n = 1e6 N/m, k_t = 2/7 k_n, e = 0.7 (force clamped at zero, ζ calibrated
for it), friction 0.5, gravity −9.81 m/s² in the plane, in a box (floor and
two side walls, soft contacts of the same law) √n granules wide; dt = t_c/50 of a granule pair.
The bed is a hexagonal packing of touching discs (monodisperse: a polydisperse bed would take
~10⁴ steps per 40 µm gap to fall shut at this dt), compressed under gravity by
``SoftGranules.relax`` and then run --settle steps without drag before timing (~3 contacts per
granule). Timing: --repeats
blocks of --steps steps per thread count, interleaved; reported is the median particle-steps/s
(n × steps / wall seconds), with the neighbour-list rebuilds of the blocks included.

    python benchmarks/soft_bed.py                     # 1,000 and 10,000 granules, 1 and 2 threads
    python benchmarks/soft_bed.py --sizes 1000 --repeats 3 --steps 500   # smoke
"""

import argparse
import math
import statistics
import time

import numba
import numpy as np

from perga.soft import SoftGranules, contact_parameters, plane, uniform_table

RADIUS = 2e-3
DENSITY = 1400.0
K_N = 1e6
E = 0.7


def bed(n: int) -> SoftGranules:
    """A dense bed of n granules in a box (see module docstring), before settling."""
    r = np.full(n, RADIUS)
    m = DENSITY * 4.0 / 3.0 * math.pi * r**3
    cols = math.ceil(math.sqrt(n))
    pitch = 2.0 * RADIUS * (1.0 - 1e-5)  # touching: 0.1 µm overlaps, settled by relax()
    idx = np.arange(n)
    row, col = idx // cols, idx % cols
    x = np.column_stack(
        [(col + 0.5 + 0.5 * (row % 2)) * pitch, RADIUS + row * pitch * math.sqrt(3.0) / 2.0]
    )
    width = (cols + 0.5) * pitch + 2.0 * RADIUS * 1e-5
    params = contact_parameters("linear", E, k_n=K_N, friction=0.5)
    walls = [
        plane((0.0, 0.0), (0.0, 1.0)),
        plane((0.0, 0.0), (1.0, 0.0)),
        plane((width, 0.0), (-1.0, 0.0)),
    ]
    return SoftGranules(x, r, m, uniform_table(params), walls=walls, gravity=(0.0, -9.81))


def settle(g: SoftGranules, steps: int) -> None:
    """Let the bed fall onto itself with drag, then run without it."""
    g.relax(v_release=0.05, max_steps=20_000)
    g.step(steps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--steps", type=int, default=2000, help="steps per timed block")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--settle", type=int, default=5000)
    args = parser.parse_args()
    print(f"numba {numba.__version__}, {numba.config.NUMBA_NUM_THREADS} threads available")
    for n in args.sizes:
        g = bed(n)
        t0 = time.perf_counter()
        settle(g, args.settle)
        pairs = int(np.diff(g.start).sum())
        contacts = g._pairs()[0].size
        print(
            f"\nn = {n}: dt = {g.dt:.3e} s (t_c = {g.t_c:.3e} s), skin = {g.skin:.2e} m, "
            f"settled in {time.perf_counter() - t0:.1f} s; listed pairs {pairs}, "
            f"contacts {contacts} ({2 * contacts / n:.2f} per granule), "
            f"KE {g.kinetic_energy():.2e} J"
        )
        rates: dict[int, list[float]] = {k: [] for k in args.threads}
        rebuilds: dict[int, int] = dict.fromkeys(args.threads, 0)
        for k in args.threads:  # warm-up (compiles for this chunk count)
            g.set_threads(k)
            g.step(10)
        for _ in range(args.repeats):
            for k in args.threads:
                g.set_threads(k)
                before = g.n_rebuilds
                t = time.perf_counter()
                g.step(args.steps)
                rates[k].append(n * args.steps / (time.perf_counter() - t))
                rebuilds[k] += g.n_rebuilds - before
        assert np.all(np.isfinite(g.x)), "non-finite positions"
        base = statistics.median(rates[args.threads[0]])
        for k in args.threads:
            med = statistics.median(rates[k])
            print(
                f"  {k} thread(s): {med / 1e6:6.2f} M particle-steps/s "
                f"(range {min(rates[k]) / 1e6:.2f}-{max(rates[k]) / 1e6:.2f}), "
                f"{1e3 * n / med:.3f} ms/step, {rebuilds[k]} rebuilds in "
                f"{args.repeats * args.steps} steps, speed-up {med / base:.2f}"
            )


if __name__ == "__main__":
    main()
