"""Physical cross-checks of a schema-valid case, run by :func:`perga.model.compile.compile_case`
on what it builds: each returns problems as "key: message" strings.

They need valid fields and names (:func:`perga.case.load.load_case` checked those): a hammer
that fits in the chamber, granules that neither overlap each other nor the wall at the start
(:func:`granule_inputs` before the placement is built, :func:`granule_placement` on it), effects
that fit the rotor's plane, restitutions a soft contact law can reach, and a time step
(:mod:`perga.model.plan`) that neither lets a granule pass through a hammer or the wall nor
turns the rotor too far in one step, and resolves soft contacts.
"""

from __future__ import annotations

import math

import numpy as np

from perga.case.schema import (
    Case,
    CombPlacement,
    ExplicitPlacement,
    Outlet,
    RandomPlacement,
    ShotPlacement,
    one_of,
)
from perga.contact.laws import LAWS, contact_law
from perga.geometry.clearance import Obstacles, overlapping_pairs
from perga.geometry.wall import circumscribed, wall_pieces
from perga.model.hammer_geometry import hammer_geometry
from perga.model.obstacles import initial_obstacles
from perga.model.parts import (
    ChamberGeometry,
    chamber_geometry,
    hinge_misses,
    hinge_positions,
    rotor_geometry,
)
from perga.model.placement import face
from perga.model.plan import MAX_ROTATION_PER_STEP, StepPlan, fastest_relative_speed
from perga.model.sizes import radius_range

MIN_STEPS_PER_CONTACT = 10
"""Fewest steps per soft contact accepted (symplectic Euler is stable to about t_c/5; e drifts
by a few per cent below t_c/20)."""

MAX_RANDOM_PACKING = 0.5
"""Largest area fraction a random non-overlapping pack of discs is asked to fill (random
sequential addition jams near 0.547 in 2-D)."""


def hammers(case: Case) -> list[str]:
    h = case.hammers
    problems = []
    if h.mount != "free" and h.velocity != (0.0, 0.0):
        problems.append(f"hammers.velocity: only for mount = 'free' (got {h.velocity})")
    if h.swing_limit is not None:
        if h.mount != "hinged":
            problems.append("hammers.swing_limit: stops are for mount = 'hinged'")
        elif abs(h.swing_angle) > h.swing_limit:
            problems.append(
                f"hammers.swing_angle: {h.swing_angle:g} rad is past the stops at "
                f"±swing_limit = {h.swing_limit:g} rad"
            )
    if h.mount == "welded" and h.swing_angle != 0.0:
        problems.append(f"hammers.swing_angle: a welded hammer is radial (got {h.swing_angle})")
    if h.angles is not None and len(h.angles) != h.count:
        problems.append(
            f"hammers.angles: needs one angle per hammer, {h.count} (got {len(h.angles)})"
        )
    try:
        geometry = hammer_geometry(case)
    except ValueError as exc:
        return [*problems, f"hammers.shape: {exc}"]
    chamber = chamber_geometry(case)
    if chamber is not None:
        reach = geometry.reach(h.hinge_radius)
        if reach >= chamber.inner_radius:
            problems.append(
                f"hammers: a hammer reaches {reach:.4g} m from the axis, past the chamber wall's "
                f"nearest point at {chamber.inner_radius:.4g} m"
            )
    hinges = hinge_positions(case)
    for k in hinge_misses(case, hinges):
        rotor = rotor_geometry(case)
        assert rotor is not None
        holes = ", ".join(f"({x:.4g}, {y:.4g})" for x, y in rotor.hinges)
        problems.append(
            f"hammers: hinge {k} at ({hinges[k][0]:.4g}, {hinges[k][1]:.4g}) m is at no hinge "
            f"hole of the rotor ({rotor.source}: holes at {holes} m); set hammers.hinge_radius, "
            "count and angles to match"
        )
    return problems


def parts(case: Case) -> list[str]:
    """The rotor disc and chamber files load (their errors name the file)."""
    problems = []
    for name, load in (("rotor.shape", rotor_geometry), ("chamber.shape", chamber_geometry)):
        try:
            load(case)
        except ValueError as exc:
            problems.append(f"{name}: {exc}")
    wall = None if problems else chamber_geometry(case)
    if wall is not None and wall.outline is not None:
        assert case.chamber is not None
        try:
            wall_pieces(wall.outline, case.chamber.wall_thickness, wall.source)
        except ValueError as exc:
            problems.append(f"chamber.wall_thickness: {exc}")
    return problems


def granule_inputs(case: Case) -> list[str]:
    """What the placement needs before it can be built: a placement, counts that match, a
    shot on the hammer's face, a random annulus that can hold the pack, comb cells that hold
    the granules. Any problem here: the placement is not built."""
    g, placement = case.granules, case.granules.placement
    if placement is None:
        return [
            "granules.placement: missing: a scene (a case with a [chamber]) needs the granules' "
            "start positions (kind = 'explicit', 'ring', 'random', 'comb' or 'shot')"
        ]
    problems = []
    if isinstance(placement, ExplicitPlacement):
        if len(placement.positions) != g.count:
            problems.append(
                f"granules.placement.positions: needs granules.count = {g.count} entries "
                f"(got {len(placement.positions)})"
            )
        for name in ("velocities", "angular_velocities"):
            given = getattr(placement, name)
            if given is not None and len(given) != len(placement.positions):
                problems.append(
                    f"granules.placement.{name}: needs one entry per position "
                    f"({len(placement.positions)}, got {len(given)})"
                )
    if isinstance(placement, ShotPlacement):
        problems += _shot(case, placement)
    if isinstance(placement, RandomPlacement):
        wall = chamber_geometry(case)
        assert wall is not None
        limit = wall.inner_radius - g.radius
        if not placement.inner_radius + g.radius <= placement.outer_radius <= limit:
            problems.append(
                "granules.placement.outer_radius: must be in [inner_radius + radius, "
                "wall's inner radius − radius] = "
                f"[{placement.inner_radius + g.radius:g}, {limit:g}] m "
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
    if isinstance(placement, CombPlacement) and placement.pitch < 2 * radius_range(case)[1]:
        problems.append(
            f"granules.placement.pitch: cells {placement.pitch:g} m apart cannot hold granules "
            f"of radius up to {radius_range(case)[1]:g} m: needs >= {2 * radius_range(case)[1]:g}"
        )
    elif isinstance(placement, CombPlacement) and g.count != placement.rows * placement.columns:
        problems.append(
            f"granules.count: a comb of {placement.rows} × {placement.columns} cells holds "
            f"{placement.rows * placement.columns} granules (got {g.count})"
        )
    return problems


def granule_placement(case: Case, positions: np.ndarray, radii: np.ndarray) -> list[str]:
    """The built placement (centres ``positions`` (n, 2), m, of granules of ``radii``, m):
    an overlap allowed below half the smallest radius, and no granule overlapping the wall, a
    hammer or another by more (a random pack is clear by construction: not checked again)."""
    placement = case.granules.placement
    if isinstance(placement, RandomPlacement):
        return []
    allowed = placement.overlap if isinstance(placement, ExplicitPlacement) else 0.0
    if not allowed < 0.5 * radii.min():
        return [
            f"granules.placement.overlap: must be below half the smallest radius, "
            f"{0.5 * radii.min():g} m (got {allowed:g})",
        ]
    return _overlaps(case, positions, radii, allowed)


def _overlaps(case: Case, positions: np.ndarray, radii: np.ndarray, allowed: float) -> list[str]:
    """Granules overlapping the wall, a hammer or each other at t = 0 by more than ``allowed``
    (m; a k-d tree: never all pairs), at most five of each named."""
    obstacles = initial_obstacles(case)
    hammers = Obstacles(obstacles.polygons)
    walls = Obstacles(container=obstacles.container, container_radius=obstacles.container_radius)
    problems = []
    for what, free in (
        ("the wall", walls.clear(positions, radii - allowed)),
        ("a hammer", hammers.clear(positions, radii - allowed)),
    ):
        bad = np.flatnonzero(~free)
        problems += [
            f"granules.placement: granule {i} at ({positions[i, 0]:.4g}, {positions[i, 1]:.4g}) m "
            f"overlaps {what} (radius {radii[i]:.4g} m)"
            for i in bad[:5]
        ]
        if len(bad) > 5:
            problems.append(f"granules.placement: ... and {len(bad) - 5} more overlap {what}")
    pairs = overlapping_pairs(positions, radii - 0.5 * allowed)
    problems += [
        f"granules.placement: granules {a} and {b} overlap (centres "
        f"{np.hypot(*(positions[a] - positions[b])):.4g} m apart, need >= "
        f"{radii[a] + radii[b] - allowed:g} m)"
        for a, b in pairs[:5]
    ]
    if len(pairs) > 5:
        problems.append(f"granules.placement: ... and {len(pairs) - 5} more overlapping pairs")
    return problems


def _shot(case: Case, placement: ShotPlacement) -> list[str]:
    """A shot is one granule aimed at hammer 0's face."""
    problems = []
    if case.granules.count != 1:
        problems.append(f"granules.count: a shot fires one granule (got {case.granules.count})")
    x0, x1, _ = face(case)
    if placement.along is not None and not x0 <= placement.along <= x1:
        problems.append(
            f"granules.placement.along: must be on hammer 0's face, [{x0:g}, {x1:g}] m from "
            f"the hinge (got {placement.along:g})"
        )
    return problems


def effects(case: Case) -> list[str]:
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


def contact_model(case: Case) -> list[str]:
    cm = case.contact_model
    if not cm.soft:
        return [
            f"contacts[{i}].{key}: sets a soft contact's stiffness; rigid contacts have none "
            f"(contact_model.kind = {one_of(LAWS)})"
            for i, contact in enumerate(case.contacts)
            for key in ("duration", "stiffness")
            if getattr(contact, key) is not None
        ]
    problems = []
    if case.solver.substeps != 1:
        problems.append(
            f"solver.substeps: must be 1 with soft contacts (got {case.solver.substeps}); "
            "contact_model.granule_substeps sets the granule steps per Pymunk step"
        )
    if not case.granules.rolls:
        problems.append(
            "granules.rolls: must be true with soft contacts (a soft granule is a disc with "
            "I = m r²/2; sliding points need contact_model.kind = 'rigid')"
        )
    law = cm.law
    if law.from_materials:
        problems += _hertz_moduli(case)
    else:
        hertz = [name for name in LAWS if contact_law(name).from_materials]
        problems += [
            f"materials.{name}.youngs_modulus: sets Hertz stiffness; a {cm.kind} contact takes "
            f"contact_model.duration or stiffness (or use kind = {one_of(hertz)})"
            for name, m in case.materials.items()
            if m.youngs_modulus is not None
        ]
    problems += _mindlin_moduli(case)
    low, high = law.reachable(cm.end)
    for i, contact in enumerate(case.contacts):
        try:
            law.damping(contact.restitution, cm.end)
        except ValueError:
            problems.append(
                f"contacts[{i}].restitution: {contact.restitution:g} is out of reach of a "
                f"{cm.kind} contact that ends at zero {cm.end}: needs e in ({low:.4g}, {high:g}]"
                + ("; contact_model.end = 'overlap' reaches any e > 0" if cm.end == "force" else "")
            )
    return problems


def _hertz_moduli(case: Case) -> list[str]:
    """The stiffness of a law that takes it from the materials (Hertz) comes from
    contact_model.stiffness or duration, shared, or from every contact material's Young's
    modulus and Poisson's ratio: one of them, whole (a pair with its own stiffness or duration
    needs neither)."""
    used = sorted(
        {m for c in case.contacts for m in c.pair
         if m in case.materials and c.stiffness is None and c.duration is None}
    )  # fmt: skip
    given = [m for m in used if case.materials[m].youngs_modulus is not None]
    shared = _shared_stiffness(case)
    if shared:
        return [
            f"materials.{m}.youngs_modulus: contact_model.{shared} already sets every Hertz "
            "pair's stiffness; give one of the two"
            for m in given
        ]
    return _missing_moduli(
        case, used, "Hertz contacts without contact_model.stiffness or duration need"
    )


def _shared_stiffness(case: Case) -> str:
    """The contact_model key that sets every pair's stiffness ('stiffness', 'duration'), or ''."""
    cm = case.contact_model
    return "stiffness" if cm.stiffness is not None else "duration" if cm.duration else ""


def _missing_moduli(case: Case, used: list[str], who: str) -> list[str]:
    """A problem for each material of ``used`` without youngs_modulus or poisson_ratio, which
    ``who`` ('… need') needs."""
    problems = []
    for m in used:
        missing = [k for k in ("youngs_modulus", "poisson_ratio")
                   if getattr(case.materials[m], k) is None]  # fmt: skip
        if missing:
            problems.append(
                f"materials.{m}: {who} {' and '.join(missing)} (Pa; -) of every material in "
                "[[contacts]]"
            )
    return problems


def _mindlin_moduli(case: Case) -> list[str]:
    """contact_model.tangential_ratio = 'mindlin' takes each pair's k_t/k_n from both materials'
    Young's modulus and Poisson's ratio: it needs them, and so the stiffness from them too."""
    if case.contact_model.tangential_ratio != "mindlin":
        return []
    shared = _shared_stiffness(case)
    if shared:
        return [
            f"contact_model.tangential_ratio: 'mindlin' takes k_t/k_n from the materials' "
            f"youngs_modulus and poisson_ratio, which contact_model.{shared} excludes; give a "
            "number (3(1 − ν)/(2 − ν) for one material on a rigid body)"
        ]
    used = sorted({m for c in case.contacts for m in c.pair if m in case.materials})
    return _missing_moduli(case, used, "contact_model.tangential_ratio = 'mindlin' needs")


def time_step(case: Case, plan: StepPlan) -> list[str]:
    """The step ``plan`` (:func:`perga.model.plan.step_plan`) against tunnelling, the rotor's
    turn and the soft contacts' resolution."""
    problems = []
    v = fastest_relative_speed(case)
    if plan.granule > plan.tunnelling:
        problems.append(
            f"solver.dt: {plan.granule:g} s lets a granule pass through a hammer or the wall at "
            f"the fastest relative speed {v:.3g} m/s: needs <= 0.5·(radius + thickness/2)/v = "
            f"{plan.tunnelling:.3g} s"
        )
    turn = case.rotor.angular_velocity * plan.machine
    if turn > MAX_ROTATION_PER_STEP:
        problems.append(
            f"solver.dt: the rotor turns {turn:.3g} rad per step; needs <= "
            f"{MAX_ROTATION_PER_STEP} rad, i.e. a step <= "
            f"{MAX_ROTATION_PER_STEP / case.rotor.angular_velocity:.3g} s"
        )
    for what, span in (
        ("the shortest contact (t_c", plan.contact_duration),
        ("a sticking contact's tangential oscillation (half-period", plan.tangential_half_period),
    ):
        steps = span / plan.granule
        if steps < MIN_STEPS_PER_CONTACT:
            problems.append(
                f"solver.dt: {plan.granule:g} s resolves {what} = {span:.3g} s) with "
                f"{steps:.3g} steps; needs >= {MIN_STEPS_PER_CONTACT} (dt <= "
                f"{span / MIN_STEPS_PER_CONTACT:.3g} s); 'auto' gives "
                "min(t_c, half-period)/contact_model.steps_per_contact"
            )
    return problems


def process(case: Case) -> list[str]:
    """Feed, outlet and damage: the region inside the chamber, an outlet granules can reach,
    the material parameters they need."""
    problems = []
    material = case.materials.get(case.granules.material)
    if case.damage is not None and (material is None or material.breakage is None):
        problems.append(
            f"damage: needs [materials.{case.granules.material}.breakage] (f_mat, w_min)"
        )
    wall = chamber_geometry(case)
    feed = case.feed
    if feed is not None:
        if feed.stop is not None and feed.stop <= feed.start:
            problems.append(f"feed.stop: must be after feed.start = {feed.start:g} s")
        if feed.kind == "comb" and not isinstance(case.granules.placement, CombPlacement):
            problems.append(
                "feed.kind: 'comb' feeds pieces shaped like granules.placement, "
                "which must then be a comb"
            )
        if wall is not None:
            r = feed.region
            c, s_ = math.cos(r.angle), math.sin(r.angle)
            corners = np.array(
                [
                    (sx * r.size[0] / 2, sy * r.size[1] / 2)
                    for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
                ]
            )
            corners = np.column_stack(
                (
                    r.centre[0] + c * corners[:, 0] - s_ * corners[:, 1],
                    r.centre[1] + s_ * corners[:, 0] + c * corners[:, 1],
                )
            )
            container = Obstacles(
                container=None if wall.outline is None else np.asarray(wall.outline),
                container_radius=wall.inner_radius if wall.outline is None else None,
            )
            if not container.clear(corners, np.zeros(4)).all():
                problems.append(
                    "feed.region: the rectangle reaches outside the chamber (corners at "
                    + ", ".join(f"({x:.4g}, {y:.4g})" for x, y in corners)
                    + " m)"
                )
    outlet = case.outlet
    if outlet is not None and wall is not None:
        problems += _outlet(outlet, wall)
    return problems


def _outlet(outlet: Outlet, wall: ChamberGeometry) -> list[str]:
    """An outlet granules can reach: a radius inside the wall's farthest point, a line or
    screen that the wall's inner outline crosses (within the screen's width)."""
    if outlet.kind == "radius":
        assert outlet.radius is not None
        if outlet.radius >= wall.outer_radius:
            return [
                f"outlet.radius: {outlet.radius:g} m is beyond the wall's farthest point "
                f"({wall.outer_radius:g} m): no granule can reach it"
            ]
        return []
    assert outlet.point is not None and outlet.normal is not None
    inner = (
        np.asarray(wall.outline)
        if wall.outline is not None
        else circumscribed(wall.inner_radius, 256)
    )
    n = np.asarray(outlet.normal) / math.hypot(*outlet.normal)
    d = inner - np.asarray(outlet.point)
    side = d @ n
    along = d @ np.array([-n[1], n[0]])
    half = 0.5 * (outlet.width if outlet.width is not None else math.inf)
    a, b = side, np.roll(side, -1)
    crossing = (a <= 0) != (b <= 0)
    t = np.where(crossing, a / np.where(crossing, a - b, 1.0), 0.0)
    where = along + t * (np.roll(along, -1) - along)
    cuts = crossing & (np.abs(where) <= half)
    touches = (np.abs(side) < 1e-9) & (np.abs(along) <= half)
    if not (cuts.any() or touches.any()):
        what = "screen" if outlet.kind == "screen" else "line"
        return [
            f"outlet: the {what} through ({outlet.point[0]:g}, {outlet.point[1]:g}) m does "
            f"not cut the chamber's wall{' within its width' if outlet.kind == 'screen' else ''}"
            ": no granule can reach it"
        ]
    return []
