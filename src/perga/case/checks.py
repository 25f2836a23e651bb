"""Physical cross-checks of a schema-valid case: each returns problems as "key: message" strings.

They run after the schema has accepted every field (a cross-check needs valid values): names that
resolve, a hammer that fits in the chamber, granules that neither overlap each other nor the wall
at the start, effects that fit the rotor's plane, and a time step that neither lets a granule
pass through a hammer or the wall nor turns the rotor too far in one step.
"""

from __future__ import annotations

import math

import numpy as np

from perga.analytic.contact import tunnelling_time_step
from perga.case.placement import initial_state
from perga.case.schema import Case, ExplicitPlacement, RandomPlacement

MAX_ROTATION_PER_STEP = 0.05
"""Largest rotor turn in one step, rad (about 3°): hinge and contact geometry stay resolved."""

MAX_RANDOM_PACKING = 0.5
"""Largest area fraction a random non-overlapping pack of discs is asked to fill (random
sequential addition jams near 0.547 in 2-D)."""


def _names(case: Case) -> list[str]:
    names = set(case.materials)
    used = [
        ("hammers.material", case.hammers.material),
        ("granules.material", case.granules.material),
    ]
    if case.chamber:
        used.append(("chamber.material", case.chamber.material))
    used += [(f"contacts[{i}].pair", n) for i, c in enumerate(case.contacts) for n in c.pair]
    problems = [
        f"{key}: unknown material {name!r} (defined: {', '.join(sorted(names))})"
        for key, name in used
        if name not in names
    ]
    if problems:
        return problems
    needed = [(case.granules.material, case.hammers.material)]
    if case.chamber:
        needed.append((case.granules.material, case.chamber.material))
    if case.effects.granule_collisions:
        needed.append((case.granules.material, case.granules.material))
    for a, b in needed:
        try:
            case.contact(a, b)
        except KeyError:
            problems.append(
                f"contacts: no entry for the pair [{a!r}, {b!r}], which this scene uses"
            )
    return problems


def _hammers(case: Case) -> list[str]:
    h = case.hammers
    problems = []
    if h.mount != "free" and h.velocity != (0.0, 0.0):
        problems.append(f"hammers.velocity: only for mount = 'free' (got {h.velocity})")
    if h.mount == "welded" and h.swing_angle != 0.0:
        problems.append(f"hammers.swing_angle: a welded hammer is radial (got {h.swing_angle})")
    if h.angles is not None and len(h.angles) != h.count:
        problems.append(
            f"hammers.angles: needs one angle per hammer, {h.count} (got {len(h.angles)})"
        )
    if h.shape.hinge_offset >= h.shape.length / 2:
        problems.append(
            f"hammers.shape.hinge_offset: must be < length/2 = {h.shape.length / 2:g} m "
            f"(got {h.shape.hinge_offset:g})"
        )
    elif case.chamber:
        reach = math.hypot(
            h.hinge_radius + h.shape.length - h.shape.hinge_offset, h.shape.width / 2
        )
        if reach >= case.chamber.radius:
            problems.append(
                f"hammers: a hammer reaches {reach:.4g} m from the axis, past the chamber wall at "
                f"chamber.radius = {case.chamber.radius:g} m"
            )
    return problems


def _granules(case: Case) -> list[str]:
    g, placement = case.granules, case.granules.placement
    if placement is None or case.chamber is None:
        return []
    problems = []
    limit = case.chamber.radius - g.radius
    if isinstance(placement, ExplicitPlacement):
        if len(placement.positions) != g.count:
            problems.append(
                f"granules.placement.positions: needs granules.count = {g.count} entries "
                f"(got {len(placement.positions)})"
            )
        if placement.velocities is not None and len(placement.velocities) != len(
            placement.positions
        ):
            problems.append(
                "granules.placement.velocities: needs one entry per position "
                f"({len(placement.positions)}, got {len(placement.velocities)})"
            )
    if isinstance(placement, RandomPlacement):
        if not placement.inner_radius + g.radius <= placement.outer_radius <= limit:
            problems.append(
                f"granules.placement.outer_radius: must be in [inner_radius + radius, "
                f"chamber.radius − radius] = [{placement.inner_radius + g.radius:g}, {limit:g}] m "
                f"(got {placement.outer_radius:g})"
            )
        else:
            area = math.pi * (placement.outer_radius**2 - placement.inner_radius**2)
            fraction = g.count * math.pi * g.radius**2 / area
            if fraction > MAX_RANDOM_PACKING:
                problems.append(
                    f"granules.count: {g.count} granules fill {fraction:.0%} of the annulus; a "
                    f"random pack needs <= {MAX_RANDOM_PACKING:.0%}: fewer granules or a wider ring"
                )
        return problems
    positions, _ = initial_state(case)
    distance = np.hypot(positions[:, 0], positions[:, 1])
    for i in np.nonzero(distance > limit)[0]:
        problems.append(
            f"granules.placement: granule {i} at {distance[i]:.4g} m from the axis overlaps the "
            f"wall (centres must be within chamber.radius − radius = {limit:.4g} m)"
        )
    if len(positions) > 1:
        gaps = np.hypot(*(positions[:, None, :] - positions[None, :, :]).transpose(2, 0, 1))
        i, j = np.nonzero(np.triu(gaps < 2 * g.radius, k=1))
        problems += [
            f"granules.placement: granules {a} and {b} overlap (centres {gaps[a, b]:.4g} m apart, "
            f"need >= 2·radius = {2 * g.radius:g} m)"
            for a, b in zip(i[:5], j[:5], strict=True)
        ]
        if len(i) > 5:
            problems.append(f"granules.placement: ... and {len(i) - 5} more overlapping pairs")
    return problems


def _effects(case: Case) -> list[str]:
    fx, rotor = case.effects, case.rotor
    problems = []
    if fx.floor_friction and rotor.plane != "horizontal":
        problems.append(
            "effects.floor_friction: needs rotor.plane = 'horizontal' (a floor under it)"
        )
    if fx.gravity_in_plane and rotor.plane != "vertical":
        problems.append("effects.gravity_in_plane: needs rotor.plane = 'vertical'")
    if fx.rotor_inertia and (rotor.inertia is None or rotor.torque_limit is None):
        problems.append(
            "effects.rotor_inertia: needs rotor.inertia (kg·m²) and rotor.torque_limit (N·m)"
        )
    if rotor.inertia is not None and not fx.rotor_inertia:
        problems.append(
            "rotor.inertia: given but effects.rotor_inertia is not listed (it would be ignored)"
        )
    if fx.hinge_friction and (case.hammers.mount != "hinged" or case.hammers.hinge_friction == 0):
        problems.append(
            "effects.hinge_friction: needs hammers.mount = 'hinged' and hammers.hinge_friction > 0"
        )
    return problems


def fastest_relative_speed(case: Case) -> float:
    """Upper bound on a granule's speed relative to a hammer or the wall, m/s: the hammer tip's
    speed on the rotor, plus a free hammer's speed, plus the fastest initial granule speed."""
    h = case.hammers
    tip = h.hinge_radius + h.shape.length - h.shape.hinge_offset
    speed = case.rotor.angular_velocity * tip + math.hypot(*h.velocity)
    placement = case.granules.placement
    if isinstance(placement, ExplicitPlacement) and placement.velocities:
        speed += float(np.max(np.hypot(*np.array(placement.velocities, dtype=float).T)))
    return speed


def thinnest_obstacle(case: Case) -> float:
    """The thinner of a hammer plate and the chamber wall, m."""
    hammer = case.hammer_plate.thickness
    return min(hammer, case.chamber.wall_thickness) if case.chamber else hammer


def resolved_time_step(case: Case) -> float:
    """solver.dt, or for 'auto' half the tunnelling bound, capped by the rotation per step, s."""
    if case.solver.dt != "auto":
        return case.solver.dt
    bound = tunnelling_time_step(
        case.granules.radius, thinnest_obstacle(case), fastest_relative_speed(case)
    )
    return min(0.5 * bound, MAX_ROTATION_PER_STEP / case.rotor.angular_velocity)


def _time_step(case: Case) -> list[str]:
    if case.chamber is None or case.granules.placement is None:
        return []
    dt = resolved_time_step(case)
    problems = []
    v = fastest_relative_speed(case)
    bound = tunnelling_time_step(case.granules.radius, thinnest_obstacle(case), v)
    if dt > bound:
        problems.append(
            f"solver.dt: {dt:g} s lets a granule pass through a hammer or the wall at the fastest "
            f"relative speed {v:.3g} m/s: needs <= 0.5·(radius + thickness/2)/v = {bound:.3g} s"
        )
    turn = case.rotor.angular_velocity * dt
    if turn > MAX_ROTATION_PER_STEP:
        problems.append(
            f"solver.dt: the rotor turns {turn:.3g} rad per step; needs <= {MAX_ROTATION_PER_STEP} "
            f"rad, i.e. dt <= {MAX_ROTATION_PER_STEP / case.rotor.angular_velocity:.3g} s"
        )
    return problems


def check_case(case: Case) -> list[str]:
    """Every cross-check's problems, in a stable order (names first: later checks need them)."""
    problems = _names(case)
    if problems:
        return problems
    for check in (_hammers, _granules, _effects, _time_step):
        problems += check(case)
    return problems
