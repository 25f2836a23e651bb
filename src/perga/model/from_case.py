"""Case (the validated case file) -> SceneSpec (the system a simulation is built from): the one
mapping.

Hammers take their outline and mass properties from :mod:`perga.case.hammer_geometry` (a plate's
rectangle, or a geometry file), in the hammer frame (hinge at the origin, axis +x), spaced
evenly on the rotor unless ``hammers.angles`` is given; granules start where the placement says
(:mod:`perga.case.placement`); only the contact pairs the scene uses are passed on; the effects
listed in the case, and only those, become the scene's effects; a soft contact model gets its
stiffness and steps from :mod:`perga.case.timestep`; ``output.vtk_3d`` adds the parts'
thicknesses for the 3-D view of the output (:class:`~perga.model.spec.DrawingSpec`).
"""

from __future__ import annotations

import math

import numpy as np

from perga.case.hammer_geometry import hammer_geometry
from perga.case.parts import chamber_geometry, hammer_angles, rotor_geometry
from perga.case.placement import comb, held, initial_spins, initial_state
from perga.case.schema import Case, CombPlacement, ContactPair
from perga.case.sizes import initial_radii, masses, mean_mass, quantile_table
from perga.case.timestep import pair_stiffness, step_plan, tangential_ratio
from perga.geometry.polygon import vertex_tuples
from perga.model.process import DamageSpec, FeedSpec, OutletSpec, ProcessSpec, Sizes
from perga.model.spec import (
    AirDragSpec,
    ChamberSpec,
    ContactSpec,
    DrawingSpec,
    DriveSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    HammerSpec,
    RigidContactSpec,
    RotorSpec,
    SceneSpec,
    SoftContactSpec,
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


def _granules(case: Case) -> tuple[GranuleSpec, ...]:
    g = case.granules
    positions, velocities = initial_state(case)
    spins = initial_spins(case)
    radii = initial_radii(case)
    weights = masses(case, radii)
    bond = case.materials[g.material].detachment_force if held(case) else None
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


def _chamber(case: Case) -> ChamberSpec:
    c, g = case.chamber, chamber_geometry(case)
    assert c is not None and g is not None
    outline = None if g.outline is None else vertex_tuples(g.outline)
    return ChamberSpec(g.inner_radius, c.wall_thickness, c.material, outline=outline)


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


def scene_spec(case: Case) -> SceneSpec:
    """The engine's description of a validated case (raises ValueError without a placement or
    a chamber: a simulation needs both)."""
    if case.chamber is None:
        raise ValueError("chamber is missing: a simulation needs the wall around the rotor")
    granules = _granules(case)
    hammers = _hammers(case)
    pairs = {frozenset((case.granules.material, case.hammers.material))}
    pairs.add(frozenset((case.granules.material, case.chamber.material)))
    if case.effects.granule_collisions:
        pairs.add(frozenset((case.granules.material,)))
    contacts = tuple(_contact(case, c) for c in case.contacts if frozenset(c.pair) in pairs)
    gravity = (0.0, -case.gravity) if case.effects.gravity_in_plane else (0.0, 0.0)
    plan = step_plan(case)
    return SceneSpec(
        rotor=_rotor(case),
        hammers=hammers,
        granules=granules,
        contacts=contacts,
        granule_dt=plan.granule,
        iterations=case.solver.iterations,
        gravity=gravity,
        granule_collisions=case.effects.granule_collisions is not None,
        chamber=_chamber(case),
        effects=_effects(case),
        contact_model=_contact_model(case),
        drawing=_drawing(case),
        plan=plan,
        process=_process(case),
    )
