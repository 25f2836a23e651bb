"""Shared dense beds for the DEM peer benchmark (``dem_peers.py``): one bed, three engines.

A bed is N monodisperse discs settled under gravity in a box (floor and two side walls, plane
walls) by perga's soft engine, saved to an npz file and exported to a LAMMPS data file, so that
perga soft, perga rigid and LAMMPS start from the identical positions.

Granules (all equal, so that LAMMPS's single ``gamma_n`` gives every pair the same damping
ratio as perga's per-contact m_eff, see ``lammps_damping``): r = 2 mm, mass of a sphere of
density 1400 kg/m³ (LAMMPS 2021 turns a per-atom density into a sphere mass 4/3 π r³ ρ even in
2-D; giving perga the same mass makes the masses equal), moment of a disc m r²/2 in both
(``fix nve/sphere disc`` in LAMMPS; without ``disc`` LAMMPS uses the sphere's 2/5 m r²).

Contact: linear spring-dashpot k_n = 1e6 N/m, k_t = 2/7 k_n, restitution 0.7 with the force
clamped at zero (perga ``end="force"``, LAMMPS ``limit_damping``), Coulomb friction 0.5 on
the total normal force, no tangential damping, no rolling resistance, the same at the walls;
dt = t_c/50 of a granule pair; Verlet skin 0.4 r.

Generation (``generate``), seeded: a loose square lattice (pitch 2.3 r, jittered) rains onto
the floor with k_n/100 (10× the time step) and comes to rest; the stiffness is then raised to
k_n/10 and to k_n, each time with a global drag of 2000/s for 12,000 steps (the bed's overlaps
shrink without flinging granules) and then without drag (40,000 and 80,000 steps); the
velocities are zeroed. One thread (numba threads slow down badly on a loaded machine). About
30 s for 1,000 granules, 9 min for 10,000 under load (cached in ``CACHE``, benchmarks/beds/).
The saved state is positions only: every engine starts at rest with empty tangential springs.
Granules are sorted into horizontal strips (row-major order) for memory locality.

    python benchmarks/beds.py 1000 10000        # generate (or show) the cached beds
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from perga.analytic.contact import LinearSpringDashpot, damping_ratio
from perga.contact.soft import SoftGranules, contact_parameters, plane, uniform_table

RADIUS = 2e-3  # m
DENSITY = 1400.0  # kg/m³
MASS = DENSITY * 4.0 / 3.0 * math.pi * RADIUS**3  # kg: sphere mass (LAMMPS's 2-D convention)
K_N = 1e6  # N/m
KT_RATIO = 2.0 / 7.0
E = 0.7
END = "force"  # force clamped at zero; ζ calibrated for it
FRICTION = 0.5
GRAVITY = 9.81  # m/s²
STEPS_PER_CONTACT = 50
SKIN = 0.4 * RADIUS  # m, perga's default for this radius; LAMMPS gets the same
SETTLE_STEPS = 80_000  # steps at the real k_n without drag before the bed is saved
RAMP_DRAG = 2000.0  # 1/s: global drag for 12,000 steps after each stiffness switch
CACHE = Path(__file__).with_name("beds")


def contact_row(k_n: float = K_N) -> np.ndarray:
    """perga's parameter row of the bed's contact law."""
    return contact_parameters("linear", E, k_n=k_n, friction=FRICTION, kt_ratio=KT_RATIO, end=END)


def contact_duration(k_n: float = K_N, m_eff: float = MASS / 2.0) -> float:
    """Duration of a head-on contact of reduced mass m_eff under the clamped law, s."""
    return LinearSpringDashpot.from_stiffness(k_n, E, m_eff, END).duration


def time_step(k_n: float = K_N) -> float:
    """t_c/50 of a granule pair (m_eff = m/2), s: the shortest contact, as perga's default."""
    return contact_duration(k_n) / STEPS_PER_CONTACT


def lammps_damping(m_eff: float, k_n: float = K_N) -> float:
    """LAMMPS ``gamma_n`` (1/s) giving perga's damping on a contact of reduced mass m_eff.

    perga: F_d = 2ζ √(k_n m_eff) δ̇ per contact; LAMMPS gran/hooke/history: F_d = m_eff γ_n δ̇.
    Equal when γ_n = 2ζ √(k_n/m_eff): exact for one m_eff only, hence the equal granules.
    """
    return 2.0 * damping_ratio(E, END) * math.sqrt(k_n / m_eff)


def wall_damping(mass: float = MASS, k_n: float = K_N) -> float:
    """Absolute normal damping η_n (kg/s) of a granule on a wall (m_eff = m): 2ζ √(k_n m)."""
    return 2.0 * damping_ratio(E, END) * math.sqrt(k_n * mass)


@dataclass
class Bed:
    """A settled bed: positions x (n, 2), m; box width, m (floor y = 0, walls x = 0 and width)."""

    x: np.ndarray
    width: float

    @property
    def n(self) -> int:
        return self.x.shape[0]

    @property
    def top(self) -> float:
        """Highest granule top, m."""
        return float(self.x[:, 1].max()) + RADIUS


def box_walls(width: float) -> list[np.ndarray]:
    """Floor at y = 0, side walls at x = 0 and x = width (perga plane rows)."""
    return [
        plane((0.0, 0.0), (0.0, 1.0)),
        plane((0.0, 0.0), (1.0, 0.0)),
        plane((width, 0.0), (-1.0, 0.0)),
    ]


def soft_bed(
    x: np.ndarray,
    width: float,
    *,
    k_n: float = K_N,
    threads: int | None = None,
    v: np.ndarray | None = None,
) -> SoftGranules:
    """perga soft granules of the bed's law at positions x (velocities v) in the box, gravity."""
    n = x.shape[0]
    return SoftGranules(
        x,
        np.full(n, RADIUS),
        np.full(n, MASS),
        uniform_table(contact_row(k_n)),
        v=v,
        walls=box_walls(width),
        gravity=(0.0, -GRAVITY),
        dt=time_step(k_n),
        skin=SKIN,
        threads=threads,
    )


def _strips(x: np.ndarray) -> np.ndarray:
    """Row-major order by horizontal strips one diameter high (memory locality)."""
    strip = np.floor(x[:, 1] / (2.0 * RADIUS))
    return np.lexsort((x[:, 0], strip))


def generate(n: int, seed: int = 1, threads: int = 1, log=print) -> Bed:
    """Rain n granules into a box √n diameters wide and settle them (module docstring)."""
    rng = np.random.default_rng(seed)
    width = math.ceil(math.sqrt(n)) * 2.0 * RADIUS
    pitch = 2.3 * RADIUS
    cols = int((width - 2.0 * RADIUS) / pitch) + 1
    idx = np.arange(n)
    x = np.column_stack(
        [
            RADIUS + (idx % cols) * pitch + rng.uniform(0.0, 0.2 * RADIUS, n),
            RADIUS + (idx // cols) * pitch + rng.uniform(0.0, 0.2 * RADIUS, n),
        ]
    )
    t0 = time.perf_counter()
    soft = soft_bed(x, width, k_n=K_N / 100.0, threads=threads)
    fall = math.sqrt(2.0 * float(x[:, 1].max()) / GRAVITY)
    soft.step(math.ceil(1.5 * fall / soft.dt) + 40_000)
    log(f"  rained at k_n/100: {time.perf_counter() - t0:.0f} s")
    for k_n, free in ((K_N / 10.0, 40_000), (K_N, SETTLE_STEPS)):
        soft = soft_bed(soft.x, width, k_n=k_n, threads=threads)
        soft.step(12_000, drag=RAMP_DRAG)
        soft.step(free)
    soft.v[:] = 0.0
    soft.w[:] = 0.0
    i, _, delta, _ = soft._pairs()
    log(
        f"  k_n/10, k_n and {SETTLE_STEPS} steps settled: {time.perf_counter() - t0:.0f} s, "
        f"{2 * i.size / n:.2f} contacts per granule, max overlap {delta.max() / RADIUS:.2e} r"
    )
    x = soft.x[_strips(soft.x)]
    return Bed(np.ascontiguousarray(x), width)


def load(n: int, seed: int = 1, cache: Path = CACHE, log=print) -> Bed:
    """The bed of n granules from the cache, generated (and saved) if missing."""
    path = cache / f"bed-{n}-seed{seed}.npz"
    if path.exists():
        data = np.load(path)
        return Bed(data["x"], float(data["width"]))
    log(f"generating the bed of {n} granules (seed {seed}) -> {path}")
    bed = generate(n, seed, log=log)
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(
        path,
        x=bed.x,
        width=bed.width,
        radius=RADIUS,
        mass=MASS,
        k_n=K_N,
        e=E,
        friction=FRICTION,
        seed=seed,
    )
    return bed


def write_lammps_data(
    path: Path,
    x: np.ndarray,
    radius: np.ndarray,
    mass: np.ndarray,
    box: tuple[float, float, float, float],
    *,
    types: np.ndarray | None = None,
    v: np.ndarray | None = None,
    w: np.ndarray | None = None,
    title: str = "perga bed (benchmarks/beds.py)",
) -> None:
    """LAMMPS data file, atom_style sphere, 2-D (z = 0, slab -r_max < z < r_max).

    box: (xlo, xhi, ylo, yhi), m. Masses are written as the density m/(4/3 π r³), which LAMMPS
    2021's read_data turns back into m in 2-D too (the benchmark checks the total mass).
    Optional types (n,) int from 1, velocities v (n, 2) and spins w (n,) about z.
    """
    n = x.shape[0]
    types = np.ones(n, int) if types is None else types
    rho = mass / (4.0 / 3.0 * math.pi * radius**3)
    r_max = float(radius.max())
    xlo, xhi, ylo, yhi = box
    lines = [
        title,
        "",
        f"{n} atoms",
        f"{int(types.max())} atom types",
        "",
        f"{xlo:.17g} {xhi:.17g} xlo xhi",
        f"{ylo:.17g} {yhi:.17g} ylo yhi",
        f"{-r_max:.17g} {r_max:.17g} zlo zhi",
        "",
        "Atoms # sphere",
        "",
    ]
    lines += [
        f"{i + 1} {types[i]} {2.0 * radius[i]:.17g} {rho[i]:.17g} {x[i, 0]:.17g} {x[i, 1]:.17g} 0"
        for i in range(n)
    ]
    if v is not None or w is not None:
        v = np.zeros((n, 2)) if v is None else v
        w = np.zeros(n) if w is None else w
        lines += ["", "Velocities", ""]
        lines += [f"{i + 1} {v[i, 0]:.17g} {v[i, 1]:.17g} 0 0 0 {w[i]:.17g}" for i in range(n)]
    path.write_text("\n".join(lines) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sizes", type=int, nargs="+")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    for n in args.sizes:
        bed = load(n, args.seed)
        soft = soft_bed(bed.x, bed.width)
        soft.step(1)
        i, _, delta, _ = soft._pairs()
        print(
            f"n = {n}: box {bed.width * 1e3:.0f} mm wide, bed {bed.top * 1e3:.0f} mm high, "
            f"{2 * i.size / n:.2f} contacts per granule, max overlap "
            f"{delta.max() / RADIUS:.2e} r, dt {soft.dt:.3e} s"
        )


if __name__ == "__main__":
    main()
