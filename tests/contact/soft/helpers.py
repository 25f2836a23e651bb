"""Single-contact impacts run through the soft kernel, with the per-step force history."""

import math
from dataclasses import dataclass

import numpy as np

from perga.contact.soft import SoftGranules, chamber, contact_parameters, plane, uniform_table

RADIUS = 2e-3
MASS = 1e-4
R_CHAMBER = 0.05


@dataclass
class Impact:
    """Outcome of one simulated impact: measured e and the sampled contact history."""

    e: float
    dt: float
    t_c: float
    peak_force: float
    peak_overlap: float
    duration: float
    granules: SoftGranules


def impact(
    model: str,
    e: float,
    v0: float,
    kind: str,
    *,
    end: str = "force",
    k_n: float | None = None,
    dt_fraction: float = 1.0 / 50.0,
    radius: float = RADIUS,
    mass: float = MASS,
    phase: float = 0.37,
    params: np.ndarray | None = None,
) -> Impact:
    """Head-on impact at approach speed v0 (m/s): ``kind`` "wall" (granule on a plane) or "pair".

    The granule(s) start ``phase`` of a step's travel before first touch (an arbitrary phase
    within the step). e = −(rebound normal speed)/v0; peak force and overlap are the largest
    sampled values; the duration runs from first touch (δ = 0, interpolated from the first
    sampled overlap and the approach speed) to the zero of the force, extrapolated linearly
    from the last two positive samples (force end) or of the overlap (overlap end). ``k_n``
    is the contact's stiffness (N/m linear, N/m^{3/2} Hertz: the table takes k_n/√R*, R* the
    radius at the wall, half of it for the pair); ``params`` a table row as it is.
    """
    if k_n is None:
        k_n = 1e6 if model == "linear" else 1e9
    if model == "hertz":
        k_n /= math.sqrt(radius if kind == "wall" else 0.5 * radius)
    row = contact_parameters(model, e, k_n=k_n, friction=0.0, end=end) if params is None else params
    table = uniform_table(row)
    if kind == "wall":
        g = SoftGranules(
            [[0.0, radius]],
            [radius],
            [mass],
            table,
            v=[[0.0, -v0]],
            walls=[plane((0.0, 0.0), (0.0, 1.0))],
            v_max=v0,
            dt_fraction=dt_fraction,
        )
        g.x[0, 1] = radius + phase * v0 * g.dt

        def overlap() -> float:
            return radius - g.x[0, 1]

        def speed() -> float:
            return -g.v[0, 1]

        def force() -> float:
            return g.f[0, 1]
    else:
        g = SoftGranules(
            [[-radius, 0.0], [radius, 0.0]],
            [radius, radius],
            [mass, mass],
            table,
            v=[[0.5 * v0, 0.0], [-0.5 * v0, 0.0]],
            v_max=v0,
            dt_fraction=dt_fraction,
        )
        g.x[0, 0] -= 0.5 * phase * v0 * g.dt
        g.x[1, 0] += 0.5 * phase * v0 * g.dt

        def overlap() -> float:
            return 2.0 * radius - (g.x[1, 0] - g.x[0, 0])

        def speed() -> float:
            return g.v[0, 0] - g.v[1, 0]

        def force() -> float:
            return -g.f[0, 0]

    times, forces, overlaps = [], [], []
    started = False
    for n in range(100_000):
        delta = overlap()
        g.step(1)
        f = force()
        if f != 0.0 or delta > 0.0:
            started = True
            times.append(n * g.dt)
            forces.append(f)
            overlaps.append(delta)
        elif started and delta < -2.0 * v0 * g.dt:
            break
    t = np.array(times)
    f = np.array(forces)
    d = np.array(overlaps)
    first = int(np.argmax(d > 0))
    t_start = t[first] - d[first] / v0
    if end == "force":
        last = int(np.flatnonzero(f > 0)[-1])
        t_end = t[last] + f[last] / (f[last - 1] - f[last]) * g.dt
    else:
        last = int(np.flatnonzero(d > 0)[-1])
        t_end = t[last] + d[last] / (d[last - 1] - d[last]) * g.dt
    return Impact(
        e=-speed() / v0,
        dt=g.dt,
        t_c=g.t_c,
        peak_force=float(f.max()),
        peak_overlap=float(d.max()),
        duration=float(t_end - t_start),
        granules=g,
    )


def chamber_gas(
    n: int,
    seed: int,
    row: np.ndarray,
    *,
    speed: float = 1.0,
    overlapping: bool = False,
    chunks: int | None = None,
) -> SoftGranules:
    """n granules (radii 0.8-1.2 RADIUS, mass ∝ r²) at random places in a round chamber of
    radius R_CHAMBER, non-overlapping unless ``overlapping``, with random velocities (speed m/s
    per component) and spins; every contact under ``row``; the pair forces in ``chunks``
    chunks (default: the kernel's)."""
    rng = np.random.default_rng(seed)
    r = RADIUS * rng.uniform(0.8, 1.2, n)
    pos: list[np.ndarray] = []
    while len(pos) < n:
        p = rng.uniform(-1, 1, 2) * (R_CHAMBER - 1.2 * RADIUS)
        if np.hypot(*p) > R_CHAMBER - 1.2 * RADIUS:
            continue
        if not overlapping and any(np.hypot(*(p - q)) < 2.5 * RADIUS for q in pos):
            continue
        pos.append(p)
    return SoftGranules(
        np.array(pos),
        r,
        MASS * (r / RADIUS) ** 2,
        uniform_table(row),
        v=speed * rng.standard_normal((n, 2)),
        w=rng.standard_normal(n) * speed / RADIUS,
        walls=[chamber(R_CHAMBER)],
        chunks=chunks,
    )
