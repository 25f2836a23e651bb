"""perga's step cost against bare Pymunk on the same scene.

Issue requirement: "a benchmark shows the engine's step cost at 1,000 and 5,000 granules within
1.2x of bare Pymunk on the same scene".

The scene: a kinematic rotor turning at OMEGA with 6 hinged plate hammers; n granules packed on
a hexagonal lattice in an annulus just outside the hinges, i.e. inside the hammers' sweep, so
the hammers plough through them from the first steps; granule-granule collisions on; a thick
round chamber wall 1 cm beyond the hammer tips keeps the bed in play (``--no-chamber``: without
it the granules leave within ~25 ms and the step cost falls with them); no gravity (horizontal
rotor). Variants:

perga           ``Simulation(System(...), record_impacts=False,
                track_energy=False).step()``: the engine's core
perga+impacts   the same with the impact recorder (begin/post_solve/separate callbacks)
perga default   ``Simulation(spec)`` with its defaults (impact recorder and energy meter)
bare callback   Pymunk written out here in the same internal units (mm, ms, g), with the same
                bodies, shapes, joints, filters, collision types and construction order as
                perga, and per-pair e and f set in one ``pre_solve`` Python callback per pair
bare shapes     the same with e and f put on the shapes (granule e, f; hammers and wall 1.0)
                and no callback at all. The contact table is factorable on purpose (e_gg =
                e_gh², f_gg = f_gh², wall = hammer values) so that the products Chipmunk forms
                are the pair values bit for bit: the same physics, no Python in the step
naive SI        "bare shapes" in metres, seconds, kilograms with Pymunk's defaults (collision
                slop 0.1, bias per second, bounding boxes inflated by 0.1·v·1 s)

perga, perga+impacts, perga default, bare callback and bare shapes are checked to end with
bit-identical granule positions.

Timing. Variants are measured in groups; in a group every repeat builds all variants afresh,
warms each up for --warmup steps (untimed: the hammers reach the granules, the bed moves), then
times --blocks blocks of --steps steps, interleaving the variants block by block (rotating who
goes first) so that machine noise hits them alike. Reported: the median ms/step over all
blocks, and the median (and range) over blocks of the paired ratio to "bare shapes" (or to
"bare callback").

    python benchmarks/engine_vs_pymunk.py                        # all groups, ~3 min, 2 cores
    python benchmarks/engine_vs_pymunk.py --groups main          # the requirement only
    python benchmarks/engine_vs_pymunk.py --sizes 1000 --repeats 1 --blocks 2   # smoke test
"""

from __future__ import annotations

import argparse
import gc
import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pymunk

from perga.engine import Simulation
from perga.model import ChamberSpec, ContactSpec, GranuleSpec, HammerSpec, RotorSpec, System

# --- the scene, SI -------------------------------------------------------------------------------

OMEGA = 100.0  # rad/s (955 rpm): hammer tips at 18 m/s
ROTOR_RADIUS = 0.09  # m
HINGE_RADIUS = 0.10  # m
N_HAMMERS = 6
HAMMER_LENGTH = 0.08  # m, hinge to tip
HAMMER_THICKNESS = 0.006  # m
HAMMER_MASS = 0.075  # kg (steel plate 80 x 6 x 20 mm)
GRANULE_RADIUS = 1.0e-3  # m
GRANULE_MASS = 5.9e-6  # kg (2 mm bee-bread ball, 1400 kg/m³)
LATTICE = 2.4 * GRANULE_RADIUS  # m, hexagonal lattice spacing (0.4 r gaps)
INNER = HINGE_RADIUS + 2 * GRANULE_RADIUS  # m, inner radius of the granule annulus
CHAMBER_RADIUS = 0.19  # m, 1 cm beyond the hammer tips
WALL_THICKNESS = 0.02  # m
WALL_SEGMENTS = 96
E_GH, F_GH = 0.7, 0.5  # granule-hammer and granule-wall restitution and friction
E_GG, F_GG = E_GH * E_GH, F_GH * F_GH  # granule-granule: factorable on purpose (see above)
ITERATIONS = 10
# no tunnelling: dt <= 0.5 (r + t/2) / v_rel,max = 0.5 · 4 mm / 30 m/s = 6.7e-5 s (tip speed
# 18 m/s, struck granules up to (1 + e) · 18 m/s)
DT = 5e-5  # s

# perga's internal units (perga.machine.units), repeated so that the bare scene owes perga nothing
LENGTH, TIME, MASS = 1e-3, 1e-3, 1e-3
SLOP = 1e-5  # m


def hammer_outline() -> tuple[tuple[float, float], ...]:
    """Plate outline in the hammer frame (hinge at the origin, axis +x), m."""
    h = HAMMER_THICKNESS / 2
    return ((0.0, -h), (HAMMER_LENGTH, -h), (HAMMER_LENGTH, h), (0.0, h))


def hammer_moment_about_hinge() -> float:
    """I_A = M (L² + t²)/12 + M (L/2)², kg·m² (uniform plate)."""
    m, length, t = HAMMER_MASS, HAMMER_LENGTH, HAMMER_THICKNESS
    return m * (length**2 + t**2) / 12 + m * (length / 2) ** 2


def hammer_angles() -> list[float]:
    return [2 * math.pi * k / N_HAMMERS for k in range(N_HAMMERS)]


def granule_positions(n: int) -> list[tuple[float, float]]:
    """n lattice sites, innermost first from INNER outwards, clear of the hammers, m."""
    r, s = GRANULE_RADIUS, LATTICE
    clearance = 1.5 * r
    reach = INNER + 2 * math.sqrt(n * s * s / math.pi) + 4 * s  # generous outer bound
    k = int(reach / s) + 2
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1), indexing="ij")
    x = (i + 0.5 * j) * s
    y = j * s * math.sqrt(3) / 2
    rho = np.hypot(x, y)
    keep = rho >= INNER
    for a in hammer_angles():
        along = x * math.cos(a) + y * math.sin(a) - HINGE_RADIUS
        across = -x * math.sin(a) + y * math.cos(a)
        keep &= ~(
            (along > -clearance)
            & (along < HAMMER_LENGTH + clearance)
            & (np.abs(across) < HAMMER_THICKNESS / 2 + clearance)
        )
    order = np.lexsort((np.arctan2(y[keep], x[keep]), rho[keep]))[:n]
    if order.size < n or rho[keep][order].max() > CHAMBER_RADIUS - clearance:
        raise RuntimeError(f"{n} granules do not fit between the hinges and the chamber")
    return [(float(a), float(b)) for a, b in zip(x[keep][order], y[keep][order], strict=True)]


@dataclass
class Variant:
    name: str
    step: Callable[[], None]
    granules: list[pymunk.Body]
    unit: float  # m per length unit of the variant


# --- perga ---------------------------------------------------------------------------------------


def perga_spec(n: int, chamber: bool) -> System:
    hammers = tuple(
        HammerSpec(
            outline=hammer_outline(),
            mass=HAMMER_MASS,
            moment_about_hinge=hammer_moment_about_hinge(),
            centre_of_mass=(HAMMER_LENGTH / 2, 0.0),
            hinge_radius=HINGE_RADIUS,
            angle_on_rotor=a,
            mount="hinged",
            material="steel",
        )
        for a in hammer_angles()
    )
    granules = tuple(
        GranuleSpec(
            position=p, velocity=(0.0, 0.0), radius=GRANULE_RADIUS, mass=GRANULE_MASS, material="bb"
        )
        for p in granule_positions(n)
    )
    contacts = [ContactSpec("bb", "steel", E_GH, F_GH), ContactSpec("bb", "bb", E_GG, F_GG)]
    extra = {}
    if chamber:
        contacts.append(ContactSpec("bb", "wall", E_GH, F_GH))
        extra["chamber"] = ChamberSpec(CHAMBER_RADIUS, WALL_THICKNESS, "wall", WALL_SEGMENTS)
    return System(
        rotor=RotorSpec(angular_velocity=OMEGA, radius=ROTOR_RADIUS),
        hammers=hammers,
        granules=granules,
        contacts=tuple(contacts),
        granule_dt=DT,
        iterations=ITERATIONS,
        granule_collisions=True,
        **extra,
    )


def build_perga(n: int, chamber: bool, name: str) -> Variant:
    spec = perga_spec(n, chamber)
    if name == "perga":
        sim = Simulation(spec, record_impacts=False, track_energy=False)
    elif name == "perga+impacts":
        sim = Simulation(spec, record_impacts=True, track_energy=False)
    else:
        sim = Simulation(spec)
    return Variant(name, sim.step, sim.contacts.bodies.granule_bodies, LENGTH)


# --- bare Pymunk ---------------------------------------------------------------------------------


def _set_pair(arbiter: pymunk.Arbiter, _space: pymunk.Space, data: tuple[float, float]) -> None:
    arbiter.restitution, arbiter.friction = data


def build_bare(
    n: int,
    chamber: bool,
    *,
    callback: bool,
    length: float,
    time_: float,
    mass: float,
    slop: float | None,
) -> tuple[pymunk.Space, list[pymunk.Body], float]:
    """The scene in Pymunk directly, every SI quantity divided by the given units. ``callback``:
    per-pair e and f in pre_solve (every shape 1.0), else on the shapes (granule e, f; hammers and
    wall 1.0). ``slop`` None keeps Pymunk's default. Returns the space, granule bodies and dt."""
    moment_unit = mass * length**2
    space = pymunk.Space()
    space.iterations = ITERATIONS
    if slop is not None:
        space.collision_slop = slop / length
    omega = OMEGA / (1.0 / time_)
    rotor = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    rotor.position = (0.0, 0.0)
    rotor.angular_velocity = omega
    space.add(rotor)

    hammer_type, granule_type, wall_type = 1, 2, 3
    outline = [(x / length, y / length) for x, y in hammer_outline()]
    moment = (hammer_moment_about_hinge() - HAMMER_MASS * (HAMMER_LENGTH / 2) ** 2) / moment_unit
    for a in hammer_angles():
        hinge = (HINGE_RADIUS * math.cos(a) / length, HINGE_RADIUS * math.sin(a) / length)
        body = pymunk.Body(HAMMER_MASS / mass, moment)
        body.center_of_gravity = (HAMMER_LENGTH / 2 / length, 0.0)
        body.angle = a
        body.position = hinge
        shape = pymunk.Poly(body, outline)
        cog = body.local_to_world(body.center_of_gravity)
        body.velocity = (-omega * cog.y, omega * cog.x)  # co-rotating
        body.angular_velocity = omega
        joint = pymunk.PivotJoint(rotor, body, hinge, (0.0, 0.0))
        joint.collide_bodies = False
        shape.filter = pymunk.ShapeFilter(group=1)  # hammers (and wall) never collide
        shape.elasticity = shape.friction = 1.0
        shape.collision_type = hammer_type
        space.add(body)
        space.add(shape)
        space.add(joint)

    bodies = []
    radius = GRANULE_RADIUS / length
    g_mass = GRANULE_MASS / mass
    g_moment = 0.5 * GRANULE_MASS * GRANULE_RADIUS**2 / moment_unit
    for x, y in granule_positions(n):
        body = pymunk.Body(g_mass, g_moment)
        body.position = (x / length, y / length)
        shape = pymunk.Circle(body, radius)
        if callback:
            shape.elasticity = shape.friction = 1.0
        else:
            shape.elasticity, shape.friction = E_GH, F_GH
        shape.collision_type = granule_type
        space.add(body)
        space.add(shape)
        bodies.append(body)

    if chamber:  # thick quadrilaterals whose inner faces touch the circle
        stretch = 1.0 / math.cos(math.pi / WALL_SEGMENTS)
        inner = CHAMBER_RADIUS / length * stretch
        outer = (CHAMBER_RADIUS + WALL_THICKNESS) / length * stretch
        for i in range(WALL_SEGMENTS):
            a0, a1 = 2 * math.pi * i / WALL_SEGMENTS, 2 * math.pi * (i + 1) / WALL_SEGMENTS
            corners = [
                (rr * math.cos(a), rr * math.sin(a))
                for rr, a in ((inner, a0), (outer, a0), (outer, a1), (inner, a1))
            ]
            shape = pymunk.Poly(space.static_body, corners)
            shape.filter = pymunk.ShapeFilter(group=1)
            shape.elasticity = shape.friction = 1.0
            shape.collision_type = wall_type
            space.add(shape)

    if callback:
        pairs = [(hammer_type, (E_GH, F_GH)), (granule_type, (E_GG, F_GG))]
        if chamber:
            pairs.insert(1, (wall_type, (E_GH, F_GH)))
        for other, data in pairs:
            space.on_collision(granule_type, other, pre_solve=_set_pair, data=data)
    return space, bodies, DT / time_


def build_bare_variant(n: int, chamber: bool, name: str) -> Variant:
    if name == "naive SI":
        space, bodies, dt = build_bare(
            n, chamber, callback=False, length=1.0, time_=1.0, mass=1.0, slop=None
        )
        unit = 1.0
    else:
        space, bodies, dt = build_bare(
            n,
            chamber,
            callback=name == "bare callback",
            length=LENGTH,
            time_=TIME,
            mass=MASS,
            slop=SLOP,
        )
        unit = LENGTH

    def step() -> None:
        space.step(dt)

    return Variant(name, step, bodies, unit)


def build(n: int, chamber: bool, name: str) -> Variant:
    if name.startswith("perga"):
        return build_perga(n, chamber, name)
    return build_bare_variant(n, chamber, name)


# --- timing --------------------------------------------------------------------------------------


@dataclass
class Result:
    times: dict[str, list[float]]  # s/step of every timed block, same block order per variant
    final: dict[str, np.ndarray]  # granule positions (m) after the last repeat
    seconds: float  # wall time of the whole measurement


def measure(
    n: int, chamber: bool, names: list[str], repeats: int, warmup: int, steps: int, blocks: int
) -> Result:
    start = time.perf_counter()
    times: dict[str, list[float]] = {name: [] for name in names}
    final: dict[str, np.ndarray] = {}
    for rep in range(repeats):
        variants = [build(n, chamber, name) for name in names]
        for v in variants:
            for _ in range(warmup):
                v.step()
        for block in range(blocks):
            shift = (rep * blocks + block) % len(variants)
            for v in variants[shift:] + variants[:shift]:
                gc.collect()
                t0 = time.perf_counter()
                for _ in range(steps):
                    v.step()
                times[v.name].append((time.perf_counter() - t0) / steps)
        final = {
            v.name: np.array([tuple(b.position) for b in v.granules]) * v.unit for v in variants
        }
        del variants
    return Result(times, final, time.perf_counter() - start)


def median_ms(values: list[float]) -> float:
    return 1e3 * statistics.median(values)


def paired_ratio(a: list[float], b: list[float]) -> tuple[float, float, float]:
    """Median, smallest and largest of the block-by-block ratios a/b."""
    ratios = [x / y for x, y in zip(a, b, strict=True)]
    return statistics.median(ratios), min(ratios), max(ratios)


GROUPS = {
    # the requirement: engine core against bare Pymunk with and without the per-pair callback
    "main": ["perga", "bare callback", "bare shapes"],
    # what perga's optional recorders cost
    "options": ["perga+impacts", "perga default", "bare shapes"],
    # what Chipmunk's game-unit defaults cost
    "si": ["bare shapes", "naive SI"],
}

COLUMNS = [
    "perga",
    "perga+impacts",
    "perga default",
    "bare callback",
    "bare shapes",
    "naive SI",
    "perga/bare callback",
    "perga/bare shapes",
    "perga+impacts/bare shapes",
    "perga default/bare shapes",
    "bare callback/bare shapes",
    "naive SI/bare shapes",
]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[1000, 5000])
    p.add_argument("--groups", nargs="+", choices=list(GROUPS), default=list(GROUPS))
    p.add_argument("--no-chamber", action="store_true", help="open scene (a transient)")
    p.add_argument("--warmup", type=int, default=150, help="untimed steps after each build")
    p.add_argument("--repeats", type=int, default=3, help="fresh builds, group 'main'")
    p.add_argument("--blocks", type=int, default=5, help="timed blocks per build")
    p.add_argument("--steps", type=int, default=20, help="steps per timed block")
    p.add_argument("--si-warmup", type=int, default=60, help="warm-up steps, group 'si'")
    p.add_argument("--si-steps", type=int, default=5, help="steps per block, group 'si'")
    args = p.parse_args(argv)
    chamber = not args.no_chamber

    print(
        f"python {platform.python_version()}, pymunk {pymunk.version}, numpy {np.__version__}, "
        f"{platform.machine()}, nproc {os.cpu_count()}, {platform.platform()}"
    )
    print(
        f"dt {DT} s, {ITERATIONS} iterations, omega {OMEGA} rad/s, {N_HAMMERS} hinged hammers, "
        f"chamber {'yes' if chamber else 'no'}"
    )
    rows: list[tuple[int, dict[str, float]]] = []
    for n in args.sizes:
        row: dict[str, float] = {}
        spread: dict[str, tuple[float, float]] = {}
        for group in args.groups:
            names = GROUPS[group]
            if group == "main":
                shape = (args.repeats, args.warmup, args.steps, args.blocks)
            elif group == "options":
                shape = (1, args.warmup, args.steps, args.blocks)
            else:
                shape = (1, args.si_warmup, args.si_steps, 2)
            res = measure(n, chamber, names, *shape)
            base = res.times["bare shapes"]
            for name in names:
                if name != "bare shapes" or group == "main":
                    row[name] = median_ms(res.times[name])
                if name != "bare shapes":
                    key = f"{name}/bare shapes"
                    row[key], *spread[key] = paired_ratio(res.times[name], base)
            if group == "main":
                key = "perga/bare callback"
                row[key], *spread[key] = paired_ratio(
                    res.times["perga"], res.times["bare callback"]
                )
            same = [k for k, v in res.final.items() if k != "naive SI"]
            identical = all(np.array_equal(res.final[k], res.final[same[0]]) for k in same)
            print(
                f"{n} granules, group {group}: {shape[0]} x ({shape[1]} warm-up + {shape[3]} x "
                f"{shape[2]} timed steps), {res.seconds:.0f} s, same final positions: "
                f"{identical if len(same) > 1 else '-'}",
                flush=True,
            )
        rows.append((n, row))
        for k in COLUMNS:
            if k in row:
                if k in spread:
                    lo, hi = spread[k]
                    print(f"  {k:28s} {row[k]:9.3f}   (blocks {lo:.3f} to {hi:.3f})")
                else:
                    print(f"  {k:28s} {row[k]:9.3f} ms/step")

    columns = [k for k in COLUMNS if any(k in r for _, r in rows)]
    print("\n| granules | " + " | ".join(columns) + " |")
    print("|---:|" + "---:|" * len(columns))
    for n, r in rows:
        print(f"| {n} | " + " | ".join(f"{r[k]:.3g}" if k in r else "-" for k in columns) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
