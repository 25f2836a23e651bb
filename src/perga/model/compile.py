"""Case (the case file, its schema and names valid) -> System (what a simulation is built from):
the one mapping, compiled once, with the physical cross-checks run on what it built.

Hammers take their outline and mass properties from :mod:`perga.model.hammer_geometry` (a plate's
rectangle, or a geometry file), in the hammer frame (hinge at the origin, axis +x), spaced
evenly on the rotor unless ``hammers.angles`` is given; granules start where the placement says
(:mod:`perga.model.placement`); only the contact pairs the scene uses are passed on; the effects
listed in the case, and only those, become the scene's effects; a soft contact model gets its
stiffness and steps from :mod:`perga.model.plan`; ``output.vtk_3d`` adds the parts'
thicknesses for the 3-D view of the output (:class:`~perga.model.system.DrawingSpec`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from perga.case.load import CaseError, load_case
from perga.case.schema import Case, CombPlacement, ContactPair
from perga.geometry.polygon import vertex_tuples
from perga.model import checks
from perga.model.hammer_geometry import hammer_geometry
from perga.model.parts import chamber_spec, hammer_angles, rotor_geometry
from perga.model.placement import PlacementError, comb, held, initial_spins, initial_state
from perga.model.plan import StepPlan, contact_plan, pair_stiffness, step_plan, tangential_ratio
from perga.model.process import DamageSpec, FeedSpec, OutletSpec, ProcessSpec, Sizes
from perga.model.sizes import initial_radii, masses, mean_mass, quantile_table
from perga.model.system import (
    AirDragSpec,
    ContactSpec,
    DrawingSpec,
    DriveSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    HammerSpec,
    RigidContactSpec,
    RotorSpec,
    SoftContactSpec,
    System,
)


def _hammers(case: Case) -> tuple[HammerSpec, ...]:
    h, g = case.hammers, hammer_geometry(case)
    return tuple(
        HammerSpec(
            outline=g.outline,
            mass=g.mass,
            moment_about_hinge=g.moment_about_hinge,
            centre_of_mass=g.centre_of_mass,
            hinge_radius=h.hinge_radius,
            angle_on_rotor=angle,
            mount=h.mount,
            material=h.material,
            swing_angle=h.swing_angle,
            swing_limit=h.swing_limit,
            velocity=h.velocity,
        )
        for angle in hammer_angles(case)
    )


def _bond_energy(case: Case) -> float:
    """The granules' material's detachment_energy, J (inf: none)."""
    energy = case.materials[case.granules.material].detachment_energy
    return math.inf if energy is None else energy


def _granules(case: Case, placement: Placement) -> tuple[GranuleSpec, ...]:
    g = case.granules
    positions, velocities, radii = placement
    spins = initial_spins(case)
    weights = masses(case, radii)
    bond = case.materials[g.material].detachment_force if held(case) else None
    bond_energy = _bond_energy(case)
    return tuple(
        GranuleSpec(
            position=(float(p[0]), float(p[1])),
            velocity=(float(v[0]), float(v[1])),
            radius=float(r),
            mass=float(m),
            material=g.material,
            rolls=g.rolls,
            angular_velocity=float(w),
            bond_force=bond,
            bond_energy=bond_energy,
        )
        for p, v, w, r, m in zip(positions, velocities, spins, radii, weights, strict=True)
    )


def _effects(case: Case) -> EffectsSpec:
    fx = case.effects
    floor = fx.floor_friction
    drag = fx.air_drag
    return EffectsSpec(
        floor_friction=FloorFrictionSpec(floor.floor, floor.friction, case.gravity)
        if floor
        else None,
        air_drag=(
            AirDragSpec(drag.air_density, drag.drag_coefficient, case.granule_thickness)
            if drag
            else None
        ),
        hinge_friction=case.hammers.hinge_friction if fx.hinge_friction else None,
        drive=(
            DriveSpec(case.rotor.inertia, case.rotor.torque_limit) if fx.rotor_inertia else None
        ),
    )


def _contact(case: Case, pair: ContactPair) -> ContactSpec:
    """A [[contacts]] entry; soft contacts with the pair's stiffness and k_t/k_n."""
    a, b = pair.pair
    if not case.contact_model.soft:
        return ContactSpec(a, b, pair.restitution, pair.friction)
    return ContactSpec(
        a,
        b,
        pair.restitution,
        pair.friction,
        pair_stiffness(case, a, b),
        tangential_ratio(case, a, b),
    )


def _contact_model(case: Case) -> RigidContactSpec | SoftContactSpec:
    cm = case.contact_model
    if not cm.soft:
        return RigidContactSpec()
    return SoftContactSpec(
        model=cm.kind,
        tangential_damping=cm.tangential_damping,
        rolling=cm.rolling,
        end=cm.end,
        substeps=cm.granule_substeps,
        threads=None if case.solver.threads == "auto" else case.solver.threads,
    )


def _rotor(case: Case) -> RotorSpec:
    disc = rotor_geometry(case)
    if disc is None:
        return RotorSpec(case.rotor.angular_velocity, case.rotor.radius)
    return RotorSpec(case.rotor.angular_velocity, disc.radius, vertex_tuples(disc.outline))


def _drawing(case: Case) -> DrawingSpec | None:
    """The 3-D view's sizes with ``output.vtk_3d`` (None without): every hammer the geometry's
    thickness, the rotor its mesh's height (else the hammers'), the chamber wall as tall as the
    tallest part, the granules ``case.granule_thickness``; m."""
    if not case.output.vtk_3d:
        return None
    hammer = hammer_geometry(case).thickness
    disc = rotor_geometry(case)
    rotor = disc.thickness if disc is not None and disc.thickness is not None else hammer
    granule = case.granule_thickness
    return DrawingSpec(
        hammer_thickness=(hammer,) * len(hammer_angles(case)),
        rotor_thickness=rotor,
        chamber_height=max(hammer, rotor, granule),
        granule_thickness=granule,
    )


def _feed(case: Case) -> FeedSpec | None:
    feed, g = case.feed, case.granules
    if feed is None:
        return None
    radii, levels, discrete = quantile_table(case)
    if feed.kind == "comb":
        assert isinstance(g.placement, CombPlacement)
        piece = comb(g.placement) - np.asarray(g.placement.centre)
        bond = case.materials[g.material].detachment_force
    else:
        piece, bond = np.zeros((1, 2)), None
    rate = feed.rate if feed.basis == "number" else feed.rate / (mean_mass(case) * len(piece))
    return FeedSpec(
        rate=rate,
        start=feed.start,
        stop=math.inf if feed.stop is None else feed.stop,
        total=feed.total,
        region=(feed.region.centre, feed.region.size, feed.region.angle),
        velocity=feed.velocity,
        piece=vertex_tuples(piece),
        sizes=Sizes(tuple(map(float, radii)), tuple(map(float, levels)), discrete),
        areal_density=case.granule_density * case.granule_thickness,
        mass=g.mass if g.size is None else None,
        material=g.material,
        rolls=g.rolls,
        bond_force=bond,
        bond_energy=_bond_energy(case),
        seed=int(np.random.SeedSequence(case.solver.seed, spawn_key=(2,)).generate_state(1)[0]),
    )


def _process(case: Case) -> ProcessSpec:
    outlet = case.outlet
    damage = case.damage
    breakage = case.materials[case.granules.material].breakage
    return ProcessSpec(
        feed=_feed(case),
        outlet=None
        if outlet is None
        else OutletSpec(
            outlet.kind,
            radius=outlet.radius if outlet.radius is not None else math.inf,
            point=outlet.point or (0.0, 0.0),
            normal=outlet.normal or (0.0, 1.0),
            width=outlet.width if outlet.width is not None else math.inf,
            aperture=outlet.aperture if outlet.aperture is not None else math.inf,
        ),
        damage=None
        if damage is None or breakage is None
        else DamageSpec(
            breakage.f_mat,
            breakage.w_min,
            damage.action,
            int(np.random.SeedSequence(case.solver.seed, spawn_key=(3,)).generate_state(1)[0]),
        ),
    )


class Placement(NamedTuple):
    """The granules' start, built once: centres (n, 2), m; velocities (n, 2), m/s; radii (n,),
    m."""

    positions: np.ndarray
    velocities: np.ndarray
    radii: np.ndarray


def compile_case(case: Case) -> System:
    """The system of a case whose schema and names are valid (:func:`perga.case.load_case`),
    built once: the parts' geometry, the placement, the sizes, the step plan and the per-pair
    plan. The physical cross-checks (:mod:`perga.model.checks`) run on what it built, in a
    stable order (the later ones need the parts, the hammers and the placement); CaseError
    lists every problem, each naming the case file."""
    if case.chamber is None:
        raise _error(case, [CHAMBER_MISSING])
    problems, geometry = _geometry_problems(case)
    if not geometry:
        raise _error(case, problems)
    placement, found = _placement(case)
    problems += found
    for check in (checks.process, checks.effects, checks.contact_model):
        problems += check(case)
    try:
        plan = step_plan(case)
    except ValueError as exc:  # an unreachable restitution, which checks.contact_model reports
        plan = None
        if not problems:
            problems.append(f"solver: no time step for this case ({exc})")
    if plan is not None:
        problems += checks.time_step(case, plan)
    if problems:
        raise _error(case, problems)
    assert placement is not None and plan is not None
    return _system(case, placement, plan)


CHAMBER_MISSING = "chamber: missing: a simulation needs the wall around the rotor"


def check_parameters(case: Case) -> None:
    """The cross-checks a case without a [chamber] (a parameter set, ``perga paper-check``)
    can have: its parts, hammers, process, effects and contact model (CaseError)."""
    problems, geometry = _geometry_problems(case)
    if geometry:
        for check in (checks.process, checks.effects, checks.contact_model):
            problems += check(case)
    if problems:
        raise _error(case, problems)


def _geometry_problems(case: Case) -> tuple[list[str], bool]:
    """The problems of the parts' and the hammers' geometry, and whether that geometry was
    built (the later checks need it)."""
    problems = checks.parts(case)
    if problems:
        return problems, False
    problems = checks.hammers(case)
    return problems, not any(p.startswith("hammers.shape:") for p in problems)


def check(case: Case) -> None:
    """Every cross-check of a case whose schema and names are valid: a scene's by compiling it
    (:func:`compile_case`), a parameter set's own (:func:`check_parameters`); CaseError."""
    if case.chamber is None:
        check_parameters(case)
    else:
        compile_case(case)


def validated(
    path: str | Path, source_dir: Path | None = None, overrides: Sequence[str] = ()
) -> Case:
    """The case file ``path`` validated whole, as ``perga validate`` does: its schema and names
    (:func:`perga.case.load_case`), then every cross-check (:func:`check`); CaseError."""
    case = load_case(path, source_dir, overrides)
    check(case)
    return case


def load_system(
    path: str | Path, source_dir: Path | None = None, overrides: Sequence[str] = ()
) -> tuple[Case, System]:
    """The case file ``path`` (:func:`perga.case.load_case`) and its system
    (:func:`compile_case`); CaseError listing every problem of either."""
    case = load_case(path, source_dir, overrides)
    return case, compile_case(case)


def _placement(case: Case) -> tuple[Placement | None, list[str]]:
    """The granules' start and the problems of it (:func:`~perga.model.checks.granule_inputs`
    before it is built, :func:`~perga.model.checks.granule_placement` on it); None where it
    cannot be built."""
    problems = checks.granule_inputs(case)
    if problems:
        return None, problems
    try:
        positions, velocities = initial_state(case)
    except PlacementError as exc:
        return None, [f"granules.placement: {exc}"]
    radii = initial_radii(case)
    return Placement(positions, velocities, radii), checks.granule_placement(case, positions, radii)


def _error(case: Case, problems: list[str]) -> CaseError:
    """``problems`` as a CaseError, each naming the case file (a case made in Python: as
    they are)."""
    if case.source_path is None:
        return CaseError(problems)
    return CaseError([f"{case.source_path}: {problem}" for problem in problems])


def _system(case: Case, placement: Placement, plan: StepPlan) -> System:
    """The system of ``case`` from its built placement and step plan."""
    assert case.chamber is not None
    granules = _granules(case, placement)
    hammers = _hammers(case)
    pairs = {frozenset((case.granules.material, case.hammers.material))}
    pairs.add(frozenset((case.granules.material, case.chamber.material)))
    if case.effects.granule_collisions:
        pairs.add(frozenset((case.granules.material,)))
    contacts = tuple(_contact(case, c) for c in case.contacts if frozenset(c.pair) in pairs)
    gravity = (0.0, -case.gravity) if case.effects.gravity_in_plane else (0.0, 0.0)
    return System(
        rotor=_rotor(case),
        hammers=hammers,
        granules=granules,
        contacts=contacts,
        granule_dt=plan.granule,
        iterations=case.solver.iterations,
        gravity=gravity,
        granule_collisions=case.effects.granule_collisions is not None,
        chamber=chamber_spec(case),
        effects=_effects(case),
        contact_model=_contact_model(case),
        drawing=_drawing(case),
        plan=plan,
        pairs=tuple(contact_plan(case, plan.granule)) if case.contact_model.soft else (),
        process=_process(case),
    )
