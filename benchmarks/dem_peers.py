"""perga soft, perga rigid, LAMMPS and a minimal kernel on the same 2-D DEM cases (issue 4).

Cases (granules and contact law of ``beds.py``: monodisperse discs, k_n = 1e6 N/m, k_t = 2/7
k_n, e = 0.7 with the force clamped at zero, friction 0.5, dt = t_c/50, skin 0.4 r):

bed      the dense settled bed of ``beds.py`` (1,000 and 10,000 granules, floor and two side
         walls, gravity), at rest, run for the same number of steps in every engine;
sheared  the same bed, sheared at t = 0 (v_x = SHEAR_SPEED · y/top, 2 m/s at the top): it
         piles against a side wall, dilates and flows (a collisional flow: 0.1-2 contacts per
         granule), so neighbour lists are rebuilt every few hundred steps (counts and cost
         are reported);
hammers  a round chamber (R = 0.19 m) with 6 plate hammers 80 x 6 mm welded to a rotor at
         100 rad/s (hinges at 0.10 m) ploughing through granules of r = 1 mm (the lattice
         annulus of ``engine_vs_pymunk.py``), no gravity; a warm-up window, then a timed one.
         perga soft runs it from the case file ``cases/mill-soft.toml`` (``[contact_model]``)
         through ``perga.case.load_case``, ``compile_case`` and ``Simulation``.

Engines:

perga soft    ``perga.contact.soft.SoftGranules`` (numba kernel), 1 and 2 threads;
LAMMPS        Debian's ``lmp`` (29 Sep 2021), ``pair_style gran/hooke/history ... limit_damping``
              with γ_n = 2ζ√(k_n/m_eff) for the pair m_eff = m/2, walls ``fix wall/gran
              granular hooke ... damping velocity limit_damping`` (η_n = 2ζ√(k_n m)), ``fix
              nve/sphere disc``; 1 MPI rank and, if ``mpirun`` exists, 2 ranks; OMP_NUM_THREADS=1
              (this build has no OPENMP package anyway). Hammers: rows of discs (radius 3 mm,
              1 mm apart) turned by ``fix move rotate``, of mass m/(√2 − 1) so that LAMMPS's
              m_eff γ_n equals perga's damping on a kinematic hammer (m_eff = m);
perga rigid   ``perga.engine`` (Pymunk impulses, e and f exact per impact, 10 iterations) at its
              own dt (RIGID_DT; tunnelling-limited, not contact-limited), one core; box walls
              and hammers are welded polygons on a rotor, the round wall a 96-gon. At 10,000
              granules it runs fewer steps (a Pymunk step costs ~10-20 ms there);
minimal       ``minimal_kernel.py`` (bed and sheared cases): a bare numba Hooke-with-history
              kernel of the same law, walls, gravity and integrator on one thread, own serial
              Verlet list (rebuilt past skin/2): the floor of what this physics costs.

Timing: every block starts every engine afresh from the same saved state (LAMMPS re-reads the
data file; "Loop time" excludes its setup, perga's first neighbour list is built untimed
too), engines interleaved, their order rotated per block. Reported: particle-steps per second
(n × steps / wall s: median and range over blocks), wall seconds per simulated second, and each
engine's speed relative to LAMMPS on one rank (median and range of the per-block ratios), and
perga soft (1 thread) against the minimal kernel ("perga soft / minimal": time ratio, same).
Neighbour rebuilds: the number in the timed run and their share of it (LAMMPS: "Neigh" of its
timing breakdown; perga: rebuilds × the time of one build on the final state).

Physics cross-checks: restitution of one impact (wall and pair) in perga soft, LAMMPS and perga
rigid; after the timed run of block 1, every engine side by side (kinetic energy, contacts per
granule, largest overlap) and the RMS distance of perga soft's (1 thread) granule positions to
LAMMPS's (1 rank) and to the minimal kernel's.

    python benchmarks/dem_peers.py --quick        # ~1.5 min, 2 idle cores (fewer steps, blocks)
    python benchmarks/dem_peers.py                # 12.5 min at load 1-6 (docs/dev/performance.md)
    python benchmarks/dem_peers.py --cases bed --sizes 10000 --blocks 5

The beds are generated on first use and cached (``beds.py``: 9 min for 10,000 granules, loaded
machine).
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

import beds
import engine_vs_pymunk as mill
import lammps_run
import minimal_kernel as minimal
import numba
import numpy as np
import pymunk
from scipy.spatial import cKDTree

from perga.analytic.contact import damping_ratio
from perga.case import load_case
from perga.contact.soft import SoftGranules, plane, uniform_table
from perga.contact.soft.neighbours import build as build_neighbours
from perga.engine import Simulation
from perga.model import ChamberSpec, ContactSpec, GranuleSpec, HammerSpec, RotorSpec, System
from perga.model.compile import compile_case

RIGID_DT = 1e-4  # s, perga rigid in the beds (design §8's Pymunk figure used the same)
SHEAR_SPEED = 2.0  # m/s, speed of the sheared bed's top at t = 0
WALL_THICKNESS = 0.02  # m, rigid engine's walls

# the mill (hammers case): geometry of engine_vs_pymunk.py, granules of density 1400 kg/m³
MILL_RADIUS = mill.GRANULE_RADIUS  # 1 mm
MILL_MASS = beds.DENSITY * 4.0 / 3.0 * math.pi * MILL_RADIUS**3
MILL_DT = beds.contact_duration(m_eff=MILL_MASS / 2.0) / beds.STEPS_PER_CONTACT
MILL_SKIN = 0.4 * MILL_RADIUS
MILL_RIGID_DT = mill.DT  # 5e-5 s
HAMMER_BEAD = mill.HAMMER_THICKNESS / 2.0  # radius of LAMMPS's hammer discs, m
HAMMER_PITCH = 1e-3  # m between them (bumps 0.04 mm deep)
MILL_CASE = Path(__file__).with_name("cases") / "mill-soft.toml"

L1 = "LAMMPS, 1 rank"
S1 = "perga soft, 1 thread"
MINIMAL = "minimal kernel"


@dataclass
class Result:
    seconds: float  # wall time of the timed steps
    steps: int
    rebuilds: int  # neighbour-list builds during them
    neigh_share: float | None  # their share of the wall time
    state: dict[str, np.ndarray]  # x (n, 2), v (n, 2), w (n,) after the timed steps (minimal:
    # and touching, its pair count)


@dataclass
class Engine:
    name: str
    n: int
    dt: float
    run: Callable[[], Result]
    results: list[Result] = field(default_factory=list)

    def rates(self) -> list[float]:
        return [self.n * r.steps / r.seconds for r in self.results]


# --- perga soft ----------------------------------------------------------------------------------


def neighbour_build_seconds(g: SoftGranules, threads: int) -> float:
    """Median wall time of one neighbour-list build of g's current state, s."""
    previous = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            build_neighbours(g.x, g.r, g.skin, g.start, g.nbr, g.hist)
            times.append(time.perf_counter() - t0)
    finally:
        numba.set_num_threads(previous)
    return statistics.median(times)


def soft_engine(make: Callable[[], SoftGranules], threads: int, warm: int, steps: int) -> Engine:
    probe = make()
    probe.set_threads(threads)
    probe.step(2)  # loads the compiled kernel for this thread count, untimed

    def run() -> Result:
        g = make()
        g.set_threads(threads)
        if warm:
            g.step(warm)
        else:
            g._pairs()  # first neighbour list, untimed (LAMMPS builds it in its setup)
        before = g.n_rebuilds
        t0 = time.perf_counter()
        g.step(steps)
        return _soft_result(g, threads, steps, before, time.perf_counter() - t0)

    name = f"perga soft, {threads} thread{'s' if threads > 1 else ''}"
    return Engine(name, probe.n, probe.dt, run)


def _soft_result(g: SoftGranules, threads: int, steps: int, before: int, seconds: float) -> Result:
    """A timed soft run's result: rebuilds since ``before`` and their share of the time, state."""
    rebuilds = g.n_rebuilds - before
    share = rebuilds * neighbour_build_seconds(g, threads) / seconds
    state = {"x": g.x.copy(), "v": g.v.copy(), "w": g.w.copy()}
    return Result(seconds, steps, rebuilds, share, state)


# --- LAMMPS --------------------------------------------------------------------------------------


def lammps_engine(
    lmp: str,
    template: str,
    workdir: Path,
    variables: dict[str, object],
    ranks: int,
    n: int,
    mass: float,
) -> Engine:
    """LAMMPS on ``template``; checks that its granules weigh n × mass (density convention)."""
    out = workdir / f"final-{ranks}.dump"

    def run() -> Result:
        log = lammps_run.run(lmp, template, workdir, variables | {"out": out}, ranks)
        total = log.value("TOTAL_MASS")
        if not math.isclose(total, n * mass, rel_tol=1e-9):
            raise RuntimeError(f"LAMMPS granule mass {total} kg, expected {n * mass} kg")
        seconds, _procs, steps, _atoms = log.loops[-1]
        neigh = log.neigh_percent[-1] / 100.0 if log.neigh_percent else None
        return Result(seconds, steps, log.builds[-1], neigh, lammps_run.read_dump(out))

    name = f"LAMMPS, {ranks} rank{'s' if ranks > 1 else ''}"
    return Engine(name, n, float(variables["dt"]), run)


def lammps_contact(mass: float) -> dict[str, object]:
    """The contact variables of the LAMMPS templates for granules of this mass."""
    return {
        "kn": beds.K_N,
        "kt": beds.KT_RATIO * beds.K_N,
        "gn": f"{beds.lammps_damping(mass / 2.0):.17g}",
        "etaw": f"{beds.wall_damping(mass):.17g}",
        "mu": beds.FRICTION,
    }


# --- the minimal kernel ------------------------------------------------------------------------


def minimal_engine(x: np.ndarray, width: float, v: np.ndarray | None, steps: int) -> Engine:
    """``minimal_kernel.py`` on the bed at x (m) in a box of this width (m), velocities v (m/s);
    its first list built untimed, as perga's."""
    probe = minimal.MinimalBed.of(x, width, v)
    probe.step(2)  # compiles or loads the kernel, untimed

    def run() -> Result:
        bed = minimal.MinimalBed.of(x, width, v)
        t0 = time.perf_counter()
        bed.step(steps)
        seconds = time.perf_counter() - t0
        times = []
        for _ in range(3):
            t1 = time.perf_counter()
            bed.build()
            times.append(time.perf_counter() - t1)
        share = bed.rebuilds * statistics.median(times) / seconds
        state = {"x": bed.x, "v": bed.v, "w": bed.w, "touching": np.asarray(bed.touching())}
        return Result(seconds, steps, bed.rebuilds, share, state)

    return Engine(MINIMAL, x.shape[0], probe.dt, run)


# --- perga rigid ---------------------------------------------------------------------------------


def rigid_engine(spec: System, warm: int, steps: int) -> Engine:
    def run() -> Result:
        sim = Simulation(spec, record_impacts=False, track_energy=False)
        for _ in range(warm):
            sim.step()
        t0 = time.perf_counter()
        for _ in range(steps):
            sim.step()
        seconds = time.perf_counter() - t0
        state = {
            "x": np.asarray(sim.frame().granules.positions),
            "v": np.asarray(sim.frame().granules.velocities),
            "w": np.asarray(sim.frame().granules.angular_velocities),
        }
        return Result(seconds, steps, 0, None, state)

    return Engine("perga rigid (Pymunk)", len(spec.granules), spec.granule_dt, run)


def rigid_box_spec(bed: beds.Bed, v: np.ndarray | None = None) -> System:
    """The bed in perga rigid: box walls welded to a resting rotor, gravity, RIGID_DT."""
    height = 1.5 * bed.top
    t = WALL_THICKNESS
    walls = (
        wall_polygon(-t, -t, bed.width + t, 0.0),
        wall_polygon(-t, 0.0, 0.0, height),
        wall_polygon(bed.width, 0.0, bed.width + t, height),
    )
    return System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.01),
        hammers=walls,
        granules=granule_specs(bed.x, beds.RADIUS, beds.MASS, v),
        contacts=rigid_contacts("wall"),
        granule_dt=RIGID_DT,
        gravity=(0.0, -beds.GRAVITY),
        granule_collisions=True,
    )


def wall_polygon(x0: float, y0: float, x1: float, y1: float) -> HammerSpec:
    """A rectangular wall welded to a resting rotor (the rigid engine has no plane walls)."""
    cx, cy = (x0 + x1) / 2.0, (y0 + y1) / 2.0
    moment = (x1 - x0) ** 2 / 12.0 + (y1 - y0) ** 2 / 12.0 + cx * cx + cy * cy  # mass 1 kg
    return HammerSpec(
        outline=((x0, y0), (x1, y0), (x1, y1), (x0, y1)),
        mass=1.0,
        moment_about_hinge=moment,
        centre_of_mass=(cx, cy),
        hinge_radius=0.0,
        angle_on_rotor=0.0,
        mount="welded",
        material="wall",
    )


def granule_specs(x, radius, mass, v=None, w=None) -> tuple[GranuleSpec, ...]:
    v = np.zeros_like(x) if v is None else v
    w = np.zeros(len(x)) if w is None else w
    return tuple(
        GranuleSpec(
            position=(float(p[0]), float(p[1])),
            velocity=(float(u[0]), float(u[1])),
            radius=radius,
            mass=mass,
            material="bb",
            angular_velocity=float(s),
        )
        for p, u, s in zip(x, v, w, strict=True)
    )


def rigid_contacts(*others: str) -> tuple[ContactSpec, ...]:
    pairs = [("bb", "bb"), *(("bb", o) for o in others)]
    return tuple(ContactSpec(a, b, beds.E, beds.FRICTION) for a, b in pairs)


# --- the cases -----------------------------------------------------------------------------------


@dataclass
class Case:
    title: str
    engines: list[Engine]
    check: Callable[[list[Engine]], list[str]]


def _bed_engines(name: str, n: int, args, lmp: str | None, workdir: Path, log, v=None):
    """The engines of a bed case (the settled bed, moving with velocities v if given) and its
    physics check."""
    bed = beds.load(n, log=log)
    steps = args.bed_steps(n)
    r, m = beds.RADIUS, beds.MASS

    def make(threads: int) -> SoftGranules:
        return beds.soft_bed(bed.x, bed.width, threads=threads, v=v)

    engines = [soft_engine(lambda t=t: make(t), t, 0, steps) for t in args.threads]
    if lmp:
        data = workdir / f"{name}-{n}.data"
        box = (-2.0 * r, bed.width + 2.0 * r, -2.0 * r, 1.5 * bed.top)
        beds.write_lammps_data(data, bed.x, np.full(n, r), np.full(n, m), box, v=v)
        variables = {
            "data": data,
            **lammps_contact(m),
            "dt": f"{beds.time_step():.17g}",
            "skin": beds.SKIN,
            "gravity": beds.GRAVITY,
            "width": f"{bed.width:.17g}",
            "warm": 0,
            "steps": steps,
        }
        engines += [lammps_engine(lmp, "bed.in", workdir, variables, k, n, m) for k in args.ranks]
    if args.rigid:
        engines.append(rigid_engine(rigid_box_spec(bed, v), 0, args.rigid_steps(n)))
    if args.minimal:
        engines.append(minimal_engine(bed.x, bed.width, v, steps))

    def check(engines: list[Engine]) -> list[str]:
        return compare(engines, n, r, m, bed.x, box_overlaps(bed.width))

    return bed, steps, engines, check


def bed_case(n: int, args, lmp: str | None, workdir: Path, log) -> Case:
    bed, steps, engines, check = _bed_engines("bed", n, args, lmp, workdir, log)
    title = f"bed, {n} granules ({bed.width * 1e3:.0f} mm box, {steps} steps)"
    return Case(title, engines, check)


def sheared_case(n: int, args, lmp: str | None, workdir: Path, log) -> Case:
    bed = beds.load(n, log=log)
    v = np.column_stack([SHEAR_SPEED * bed.x[:, 1] / bed.top, np.zeros(n)])
    bed, steps, engines, check = _bed_engines("sheared", n, args, lmp, workdir, log, v)
    title = (
        f"sheared bed, {n} granules (the bed with v_x = {SHEAR_SPEED:g} m/s · y/top at "
        f"t = 0, {steps} steps)"
    )
    return Case(title, engines, check)


def hammer_lammps_data(path: Path, x: np.ndarray) -> int:
    """Granules (type 1) and the hammers as rows of discs (type 2); returns the hammer discs."""
    s = np.arange(
        mill.HINGE_RADIUS + HAMMER_BEAD,
        mill.HINGE_RADIUS + mill.HAMMER_LENGTH - HAMMER_BEAD + 1e-9,
        HAMMER_PITCH,
    )
    rows = [np.column_stack([s * math.cos(a), s * math.sin(a)]) for a in mill.hammer_angles()]
    hammers = np.concatenate(rows)
    n, k = len(x), len(hammers)
    radius = np.concatenate([np.full(n, MILL_RADIUS), np.full(k, HAMMER_BEAD)])
    # LAMMPS's m_eff = m m_h/(m + m_h) = m/√2 makes m_eff γ_n = 2ζ√(k_n m): perga's kinematic
    # hammer (m_eff = m)
    mass = np.concatenate([np.full(n, MILL_MASS), np.full(k, MILL_MASS / (math.sqrt(2.0) - 1))])
    types = np.concatenate([np.ones(n, int), np.full(k, 2)])
    half = mill.CHAMBER_RADIUS + 0.01
    box = (-half, half, -half, half)
    omega = mill.OMEGA
    allx = np.concatenate([x, hammers])
    v = np.zeros_like(allx)
    v[n:] = omega * np.column_stack([-hammers[:, 1], hammers[:, 0]])
    w = np.concatenate([np.zeros(n), np.full(k, omega)])
    beds.write_lammps_data(path, allx, radius, mass, box, types=types, v=v, w=w)
    return k


def mill_case(x: np.ndarray, workdir: Path, substeps: int | None = None) -> System:
    """The scene of benchmarks/cases/mill-soft.toml with the granules at x (and granule_substeps
    if given), through perga's case loader (schema and cross-checks) and ``compile_case``."""
    text = MILL_CASE.read_text()
    positions = ", ".join(f"[{a:.17g}, {b:.17g}]" for a, b in x)
    changes = [
        ("count = 1\n", f"count = {len(x)}\n"),
        ("positions = [[0.0, 0.104]]", f"positions = [{positions}]"),
    ]
    if substeps is not None:
        changes.append(("granule_substeps = 100 ", f"granule_substeps = {substeps} "))
    for old, new in changes:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    path = workdir / MILL_CASE.name
    path.write_text(text)
    spec = compile_case(load_case(path))
    assert spec.contact_model.kind != "rigid" and math.isclose(
        spec.granule_dt, MILL_DT, rel_tol=1e-12
    )
    return spec


def soft_mill_engine(spec: System, threads: int, warm: int, steps: int) -> Engine:
    """perga soft in the hammer scene: ``Simulation`` (Pymunk rotor and hammers, soft
    granules), impact recorder and energy meter off, the pair forces in ``threads`` chunks
    (``solver.threads``), computed by as many threads as the run's rule allows (never more than
    the free cores: a block that got fewer says so); one call = the contact model's substeps."""
    substeps = spec.contact_model.substeps
    spec = replace(spec, contact_model=replace(spec.contact_model, threads=threads))

    def make():
        return Simulation(spec, record_impacts=False, track_energy=False)

    make().step()  # compiles or loads the kernel, untimed

    def run() -> Result:
        sim = make()
        g = sim.contacts.granules
        for _ in range(warm // substeps):
            sim.step()
        before = g.n_rebuilds
        t0 = time.perf_counter()
        for _ in range(steps // substeps):
            sim.step()
        seconds = time.perf_counter() - t0
        if g.threads < threads:
            print(f"  (perga soft: {g.threads} of {threads} threads at the end: no more than the "
                  "free cores)")  # fmt: skip
        return _soft_result(g, threads, steps, before, seconds)

    name = f"perga soft, {threads} thread{'s' if threads > 1 else ''}"
    return Engine(name, len(spec.granules), spec.granule_dt, run)


def hammers_case(n: int, args, lmp: str | None, workdir: Path, log) -> Case:
    x = np.array(mill.granule_positions(n))
    warm, steps = args.mill_steps()
    engines: list[Engine] = []
    soft_spec = mill_case(x, workdir, args.mill_substeps)
    substeps = soft_spec.contact_model.substeps
    if warm % substeps or steps % substeps:
        raise SystemExit(f"hammers: warm-up and timed steps must be multiples of {substeps}")
    log(f"  perga soft: {MILL_CASE.name}, granule_substeps = {substeps}")
    engines += [soft_mill_engine(soft_spec, t, warm, steps) for t in args.threads]
    if lmp:
        data = workdir / f"mill-{n}.data"
        k = hammer_lammps_data(data, x)
        log(f"  LAMMPS hammers: {k} discs of radius {HAMMER_BEAD * 1e3:g} mm")
        variables = {
            "data": data,
            **lammps_contact(MILL_MASS),
            "dt": f"{MILL_DT:.17g}",
            "skin": MILL_SKIN,
            "R": mill.CHAMBER_RADIUS,
            "period": f"{2.0 * math.pi / mill.OMEGA:.17g}",
            "warm": warm,
            "steps": steps,
        }
        engines += [
            lammps_engine(lmp, "hammers.in", workdir, variables, r, n, MILL_MASS)
            for r in args.ranks
        ]
    if args.rigid:
        hammers = tuple(
            HammerSpec(
                outline=mill.hammer_outline(),
                mass=mill.HAMMER_MASS,
                moment_about_hinge=mill.hammer_moment_about_hinge(),
                centre_of_mass=(mill.HAMMER_LENGTH / 2.0, 0.0),
                hinge_radius=mill.HINGE_RADIUS,
                angle_on_rotor=a,
                mount="welded",
                material="steel",
            )
            for a in mill.hammer_angles()
        )
        spec = System(
            rotor=RotorSpec(angular_velocity=mill.OMEGA, radius=mill.ROTOR_RADIUS),
            hammers=hammers,
            granules=granule_specs(x, MILL_RADIUS, MILL_MASS),
            contacts=rigid_contacts("steel", "wall"),
            granule_dt=MILL_RIGID_DT,
            granule_collisions=True,
            chamber=ChamberSpec(mill.CHAMBER_RADIUS, WALL_THICKNESS, "wall", 96),
        )
        t_warm, t_steps = warm * MILL_DT, steps * MILL_DT
        engines.append(
            rigid_engine(
                spec, round(t_warm / MILL_RIGID_DT), max(round(t_steps / MILL_RIGID_DT), 1)
            )
        )

    def check(engines: list[Engine]) -> list[str]:
        return compare(
            engines, n, MILL_RADIUS, MILL_MASS, None, round_overlaps(mill.CHAMBER_RADIUS)
        )

    title = (
        f"hammers, {n} granules (6 welded plate hammers at {mill.OMEGA:g} rad/s, "
        f"{warm} steps warm-up + {steps} timed = {1e3 * (warm + steps) * MILL_DT:.2f} ms)"
    )
    return Case(title, engines, check)


# --- physics cross-checks ------------------------------------------------------------------------


def box_overlaps(width: float) -> Callable[[np.ndarray, float], np.ndarray]:
    def overlaps(x: np.ndarray, r: float) -> np.ndarray:
        return np.concatenate([r - x[:, 1], r - x[:, 0], r - (width - x[:, 0])])

    return overlaps


def round_overlaps(radius: float) -> Callable[[np.ndarray, float], np.ndarray]:
    def overlaps(x: np.ndarray, r: float) -> np.ndarray:
        return r + np.hypot(x[:, 0], x[:, 1]) - radius

    return overlaps


def contact_figures(x: np.ndarray, r: float, walls) -> tuple[float, float]:
    """(granule-granule contacts per granule, largest overlap / r, walls included)."""
    pairs = cKDTree(x).query_pairs(2.0 * r, output_type="ndarray")
    delta = 2.0 * r - np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    largest = max(float(delta.max(initial=0.0)), float(walls(x, r).max(initial=0.0)))
    return 2.0 * int((delta > 0).sum()) / len(x), largest / r


def compare(engines, n, r, m, x0, walls) -> list[str]:
    """Every engine after the timed run of the first block; perga soft (1 thread) against LAMMPS
    (1 rank) and the minimal kernel."""
    inertia = 0.5 * m * r * r
    lines = []
    states = {e.name: e.results[0].state for e in engines if e.results}
    for name, s in states.items():
        ke = 0.5 * m * float(np.sum(s["v"] ** 2)) + 0.5 * inertia * float(np.sum(s["w"] ** 2))
        cpg, largest = contact_figures(s["x"], r, walls)
        text = f"{name:22s} KE {ke:.4e} J, {cpg:.2f} contacts/granule, max overlap {largest:.2e} r"
        if x0 is not None:
            moved = np.linalg.norm(s["x"] - x0, axis=1)
            text += f", mean displacement {moved.mean() / r:.2e} r"
        if "touching" in s:
            text += f" ({int(s['touching']) / n:.3f} touching pairs/granule, its own count)"
        lines.append(text)
    soft = states.get(S1)
    for name, other in ((L1, "LAMMPS"), (MINIMAL, "minimal")):
        if soft is not None and name in states:
            d = np.linalg.norm(soft["x"] - states[name]["x"], axis=1)
            lines.append(
                f"perga soft vs {other}: granule positions differ by "
                f"{np.sqrt(np.mean(d**2)) / r:.2e} r RMS, {d.max() / r:.2e} r at most"
            )
    return lines


def soft_impact(mode: str, v0: float, dt: float) -> float:
    """Restitution of one head-on impact in perga soft (same start as impact.in)."""
    r, m = beds.RADIUS, beds.MASS
    table = uniform_table(beds.contact_row())
    if mode == "wall":
        g = SoftGranules(
            [[0.0, r + 0.5 * v0 * dt]], [r], [m], table, v=[[0.0, -v0]],
            walls=[plane((0.0, 0.0), (0.0, 1.0))], dt=dt,
        )  # fmt: skip
    else:
        g = SoftGranules(
            [[0.0, 0.01], [0.0, 0.01 + 2.0 * r + v0 * dt]], [r, r], [m, m], table,
            v=[[0.0, 0.5 * v0], [0.0, -0.5 * v0]], dt=dt,
        )  # fmt: skip
    g.step(math.ceil(3.0 * beds.contact_duration(m_eff=m) / dt))
    return float(g.v[0, 1] / v0 if mode == "wall" else (g.v[1, 1] - g.v[0, 1]) / v0)


def rigid_impact(v0: float) -> float:
    r, m = beds.RADIUS, beds.MASS
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.01),
        hammers=(wall_polygon(-0.02, -0.02, 0.02, 0.0),),
        granules=granule_specs(np.array([[0.0, r + 1e-3]]), r, m, np.array([[0.0, -v0]])),
        contacts=(ContactSpec("bb", "wall", beds.E, 0.0),),
        granule_dt=RIGID_DT,
    )
    sim = Simulation(spec, record_impacts=False, track_energy=False)
    for _ in range(50):
        sim.step()
    return float(sim.frame().granules.velocities[0][1] / v0)


def restitution_checks(lmp: str | None, workdir: Path, refinements) -> list[str]:
    dt = beds.time_step()
    t0 = time.perf_counter()
    lines = ["restitution of one head-on impact at 1 m/s (target 0.7), dt = t_c/50 / f:"]
    for f in refinements:
        parts = [f"perga soft wall {soft_impact('wall', 1.0, dt / f):.4f}"]
        parts.append(f"pair {soft_impact('pair', 1.0, dt / f):.4f}")
        if lmp:
            base = {
                "r": beds.RADIUS,
                "rho": beds.DENSITY,
                "v0": 1.0,
                **lammps_contact(beds.MASS),
                "gnw": 2.0 * damping_ratio(beds.E, "overlap") * math.sqrt(beds.K_N / beds.MASS),
                "dt": f"{dt / f:.17g}",
                "nsteps": math.ceil(3.0 * beds.contact_duration(m_eff=beds.MASS) / (dt / f)),
            }
            runs = {
                key: lammps_run.run(lmp, "impact.in", workdir, base | {"mode": mode, "wall": wall})
                for key, mode, wall in (
                    ("wall", "wall", "granular"),
                    ("pair", "pair", "granular"),
                    ("old", "wall", "classic"),
                )
            }
            wall, pair, old = runs["wall"], runs["pair"], runs["old"]
            parts.append(f"LAMMPS wall {wall.value('VY1'):.4f}")
            parts.append(f"pair {pair.value('VY2') - pair.value('VY1'):.4f}")
            parts.append(f"classic unclamped wall (ζ for 'overlap') {old.value('VY1'):.4f}")
        lines.append(f"  f = {f}: " + ", ".join(parts))
    lines.append(f"  perga rigid (Pymunk, dt {RIGID_DT:g} s): wall {rigid_impact(1.0):.4f}")
    lines.append(f"  ({time.perf_counter() - t0:.0f} s)")
    return lines


# --- running and reporting -----------------------------------------------------------------------


def paired(a: Engine, b: Engine) -> tuple[float, float, float]:
    """Median, smallest and largest per-block ratio of a's speed to b's."""
    ratios = [x / y for x, y in zip(a.rates(), b.rates(), strict=True)]
    return statistics.median(ratios), min(ratios), max(ratios)


def load_average() -> str:
    return "/".join(f"{v:.2f}" for v in os.getloadavg())


def measure(case: Case, blocks: int, log) -> None:
    for b in range(blocks):
        shift = b % len(case.engines)
        for engine in case.engines[shift:] + case.engines[:shift]:
            engine.results.append(engine.run())
        log(f"  block {b + 1}/{blocks} done, load {load_average()}")


def report(case: Case, log) -> list[str]:
    """Prints the case's figures; returns its Markdown table rows."""
    base = next((e for e in case.engines if e.name == L1), None)
    rows = []
    for e in case.engines:
        rates = e.rates()
        rate = statistics.median(rates)
        wall_per_sim = statistics.median(r.seconds / (r.steps * e.dt) for r in e.results)
        rebuilds = statistics.median(r.rebuilds for r in e.results)
        shares = [r.neigh_share for r in e.results if r.neigh_share is not None]
        share = f"{100 * statistics.median(shares):.0f} %" if shares else "-"
        ratio = "-"
        if base is not None:
            med, lo, hi = paired(e, base)
            ratio = f"{med:.2f} ({lo:.2f}-{hi:.2f})"
        steps = e.results[0].steps
        log(
            f"  {e.name:22s} {rate / 1e6:7.2f} M particle-steps/s "
            f"({min(rates) / 1e6:.2f}-{max(rates) / 1e6:.2f}), {wall_per_sim:10.1f} wall s per "
            f"simulated s, x LAMMPS 1 rank {ratio}, {steps} steps of {e.dt:.3g} s, "
            f"{rebuilds:g} rebuilds ({share})"
        )
        rows.append(
            f"| {case.title.split(',')[0]} | {e.n} | {e.name} | {steps} x {e.dt:.3g} s | "
            f"{rate / 1e6:.2f} ({min(rates) / 1e6:.2f}-{max(rates) / 1e6:.2f}) | "
            f"{wall_per_sim:.1f} | {ratio} | {rebuilds:g} | {share} |"
        )
    two = {e.name: e for e in case.engines}
    if "perga soft, 2 threads" in two and "LAMMPS, 2 ranks" in two:
        med, lo, hi = paired(two["perga soft, 2 threads"], two["LAMMPS, 2 ranks"])
        log(f"  perga soft 2 threads / LAMMPS 2 ranks: {med:.2f} ({lo:.2f}-{hi:.2f})")
    if S1 in two and MINIMAL in two:
        med, lo, hi = paired(two[MINIMAL], two[S1])
        log(f"  perga soft / minimal (1 thread, time ratio): {med:.2f} ({lo:.2f}-{hi:.2f})")
    for line in case.check(case.engines):
        log(f"  {line}")
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="fewer steps and blocks (~3 min)")
    cases = ["bed", "sheared", "hammers"]
    p.add_argument("--cases", nargs="+", choices=cases, default=cases)
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 10000], help="bed granules")
    p.add_argument("--mill-granules", type=int, default=3000, help="hammer case granules")
    p.add_argument(
        "--mill-substeps", type=int, help="granule steps per Pymunk step (default: the case's)"
    )
    p.add_argument("--blocks", type=int, help="timed blocks per engine (default 5, quick 3)")
    p.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="perga soft threads")
    p.add_argument("--no-mpi", action="store_true", help="LAMMPS on one rank only")
    p.add_argument("--no-lammps", action="store_true")
    p.add_argument("--no-rigid", action="store_true")
    p.add_argument("--no-minimal", action="store_true", help="no minimal kernel line (beds)")
    args = p.parse_args(argv)
    quick = args.quick
    blocks = args.blocks or (3 if quick else 5)
    small = {"bed": 3000 if quick else 20000, "rigid": 30 if quick else 200}
    large = {"bed": 1000 if quick else 3000, "rigid": 5 if quick else 40}
    args.bed_steps = lambda n: (small if n <= 2000 else large)["bed"]
    args.rigid_steps = lambda n: (small if n <= 2000 else large)["rigid"]
    args.mill_steps = lambda: (1000, 2000) if quick else (5000, 10000)
    args.impact_refinements = (1,) if quick else (1, 10)
    args.rigid = not args.no_rigid
    args.minimal = not args.no_minimal

    def log(text: str = "") -> None:
        print(text, flush=True)

    lmp = None if args.no_lammps else lammps_run.binary()
    args.ranks = [1] if args.no_mpi or lammps_run.mpirun() is None else [1, 2]
    log(
        f"{platform.node()}: {platform.processor() or platform.machine()}, nproc "
        f"{os.cpu_count()}, {platform.platform()}; python {platform.python_version()}, numba "
        f"{numba.__version__}, numpy {np.__version__}, pymunk {pymunk.version}"
    )
    log(f"LAMMPS: {lammps_run.version(lmp) if lmp else 'not found (apt-get install lammps)'}")
    log(f"load average at start {load_average()}; {blocks} blocks per engine")
    start = time.perf_counter()
    rows: list[str] = []
    with tempfile.TemporaryDirectory(prefix="perga-peers-") as tmp:
        workdir = Path(tmp)
        for line in restitution_checks(lmp, workdir, args.impact_refinements):
            log(line)
        plan = [(c, n) for c in args.cases if c != "hammers" for n in args.sizes]
        if "hammers" in args.cases:
            plan.append(("hammers", args.mill_granules))
        builders = {"bed": bed_case, "sheared": sheared_case, "hammers": hammers_case}
        for name, n in plan:
            t0 = time.perf_counter()
            case = builders[name](n, args, lmp, workdir, log)
            log(f"\n{case.title}, load {load_average()}")
            measure(case, blocks, log)
            rows += report(case, log)
            log(f"  ({time.perf_counter() - t0:.0f} s)")
    log(f"\nwall time {time.perf_counter() - start:.0f} s, load average at end {load_average()}")
    log(
        "\n| case | granules | engine | steps x dt | M particle-steps/s (range) | wall s per "
        "simulated s | x LAMMPS 1 rank (range) | rebuilds | rebuild share |"
    )
    log("|---|---:|---|---|---:|---:|---:|---:|---:|")
    for row in rows:
        log(row)
    return 0


if __name__ == "__main__":
    sys.exit(main())
