"""Effects are built only when listed (design §3), and the chamber wall."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pymunk
import pytest

from perga.engine import Simulation
from perga.machine import units
from perga.machine.effects import AirDrag, FloorFriction
from perga.model import (
    AirDragSpec,
    ChamberSpec,
    ContactSpec,
    DriveSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    RotorSpec,
    System,
)
from tests.engine.helpers import plate

EFFECTS = {
    "floor_friction": FloorFrictionSpec("corotating", 0.3),
    "air_drag": AirDragSpec(air_density=1.2, drag_coefficient=1.0, thickness=0.002),
    "hinge_friction": 0.05,
    "drive": DriveSpec(inertia=0.05, torque_limit=5.0),
}


def _sim(**effects: object) -> Simulation:
    hammers = tuple(
        plate(
            -0.01,
            0.09,
            -0.01,
            0.01,
            0.078,
            hinge_radius=0.1,
            angle_on_rotor=phi,
            mount=mount,
            material="steel",
        )
        for phi, mount in ((0.0, "hinged"), (3.0, "welded"))
    )
    granules = tuple(
        GranuleSpec(position=(0.0, y), velocity=(1.0, 0.0), radius=0.002, mass=50e-6, material="bb")
        for y in (0.05, 0.06)
    )
    spec = System(
        rotor=RotorSpec(angular_velocity=50.0, radius=0.2),
        hammers=hammers,
        granules=granules,
        contacts=(ContactSpec("bb", "steel", 0.5, 0.3), ContactSpec("bb", "wall", 0.5, 0.3)),
        granule_dt=1e-5,
        chamber=ChamberSpec(radius=0.25, wall_thickness=0.02, material="wall"),
        effects=EffectsSpec(**effects),  # type: ignore[arg-type]
    )
    return Simulation(spec)


def _trace(sim: Simulation) -> dict[str, object]:
    """Everything an effect could leave in the space."""
    space = sim.machine.space
    handlers = sim.contacts.bodies.handlers  # type: ignore[attr-defined]
    return {
        "handlers": sorted(handlers),
        "callbacks": sum(len(v) for v in handlers.values()),
        "constraints": len(space.constraints),
        "constraint_hooks": [(c.pre_solve, c.post_solve) for c in space.constraints],
        "velocity_funcs": [b.velocity_func is pymunk.Body.update_velocity for b in space.bodies],
        "rotor_type": sim.machine.rotor.body_type,
        "effects": len(sim.machine.effects),
        "kicked": _kicked(sim),
    }


def _kicked(sim: Simulation) -> list[int]:
    """Bodies (indices in space.bodies, static body last) whose state the effects' kicks (run
    by Simulation.step before everything else) change, run once here."""
    space = sim.machine.space
    bodies = [*space.bodies, space.static_body]

    def state() -> list[tuple[float, ...]]:
        return [(*b.position, b.angle, *b.velocity, b.angular_velocity) for b in bodies]

    before = state()
    if sim.kicks is not None:
        sim.kicks.run(sim.dt)
    return [i for i, (a, b) in enumerate(zip(before, state(), strict=True)) if a != b]


def test_no_effect_leaves_no_trace() -> None:
    bare = _trace(_sim())
    assert bare["constraints"] == 1  # the hinge's pivot only
    assert bare["constraint_hooks"] == [(None, None)]
    assert all(bare["velocity_funcs"])
    assert bare["rotor_type"] == pymunk.Body.KINEMATIC
    assert bare["effects"] == 0
    assert bare["kicked"] == []


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_each_effect_installs_only_itself(name: str) -> None:
    """Listing one effect changes exactly what that effect is made of, and no handler."""
    bare, one = _trace(_sim()), _trace(_sim(**{name: EFFECTS[name]}))
    changed = {key for key in bare if bare[key] != one[key]}
    expected = {
        "floor_friction": {"kicked", "effects"},
        "air_drag": {"kicked", "effects"},
        "hinge_friction": {"constraints", "constraint_hooks", "effects"},
        "drive": {"constraints", "constraint_hooks", "rotor_type", "effects"},
    }[name]
    assert changed == expected
    if "kicked" in changed:  # the granules' velocities, nothing else of any body
        sim = _sim(**{name: EFFECTS[name]})
        bodies = [*sim.machine.space.bodies, sim.machine.space.static_body]
        granules = set(sim.contacts.bodies.granule_bodies)  # type: ignore[attr-defined]
        assert {bodies[i] for i in _trace(sim)["kicked"]} == granules  # type: ignore[attr-defined]


def test_both_kicks_share_one_runner() -> None:
    """Floor friction and air drag together: one batch read and write per step, by one runner
    (floor friction, then drag on the result)."""
    sim = _sim(floor_friction=EFFECTS["floor_friction"], air_drag=EFFECTS["air_drag"])
    floor, drag = sim.machine.effects
    assert isinstance(floor, FloorFriction) and isinstance(drag, AirDrag)
    assert sim.kicks is not None and sim.kicks.kicks == [floor, drag]


def _per_granule(sim: Simulation, dt: float) -> tuple[list[pymunk.Vec2d], float, float, float]:
    """Reference: the kicks as the scalar per-body formulas of their docstrings (floor friction
    then drag), and the energy each removes / the floor supplies, internal units."""
    spec = sim.spec.effects
    assert spec.floor_friction is not None and spec.air_drag is not None
    a = units.to_internal(spec.floor_friction.friction * spec.floor_friction.gravity,
                          units.ACCELERATION)  # fmt: skip
    w = sim.machine.rotor.angular_velocity
    out, removed, supplied, dragged = [], 0.0, 0.0, 0.0
    for g, body in zip(sim.spec.granules, sim.contacts.bodies.granule_bodies, strict=True):
        v, p, m = body.velocity, body.position, body.mass
        floor = pymunk.Vec2d(-w * p.y, w * p.x)
        relative = v - floor
        speed = relative.length
        if speed > 0:
            after = relative * (1.0 - min(a * dt, speed) / speed)
            v = floor + after
            removed += 0.5 * m * (speed * speed - after.dot(after))
            supplied += m * (after - relative).dot(floor)
        k = units.to_internal(
            0.5 * spec.air_drag.air_density * spec.air_drag.drag_coefficient * 2 * g.radius
            * spec.air_drag.thickness / g.mass, 1.0 / units.LENGTH,
        )  # fmt: skip
        speed = v.length
        if speed > 0:
            after_speed = speed / (1.0 + k * speed * dt)
            dragged += 0.5 * m * (speed * speed - after_speed * after_speed)
            v = v * (after_speed / speed)
        out.append(v)
    return out, removed, supplied, dragged


def test_kicks_match_the_per_granule_formulas() -> None:
    """The array kicks against the scalar formulas, granule by granule, over states that cover
    a stopping (clamped) granule, one exactly at the floor's velocity and fast ones: velocities
    and energies to 1e-14 (rounding of the same expressions in another order)."""
    granules = [
        GranuleSpec(
            position=(0.03 * np.cos(t), 0.03 * np.sin(t)),
            velocity=(vx, vy),
            radius=0.002,
            mass=m,
            material="bb",
        )
        for t, vx, vy, m in (
            (0.0, 0.0, 50.0 * 0.03 + 1e-5, 50e-6),  # 1e-5 m/s relative: stops (clamped)
            (np.pi / 2, -50.0 * 0.03, 0.0, 60e-6),  # set exactly co-moving with the floor below
            (1.0, 3.0, -2.0, 40e-6),
            (2.5, -7.0, 0.5, 80e-6),
            (4.0, 0.0, 0.0, 50e-6),
        )
    ]
    spec = dataclasses.replace(
        _sim().spec,
        granules=tuple(granules),
        effects=EffectsSpec(floor_friction=EFFECTS["floor_friction"], air_drag=EFFECTS["air_drag"]),
    )
    sim = Simulation(spec)
    bodies = sim.contacts.bodies.granule_bodies  # type: ignore[attr-defined]
    w, co_moving = sim.machine.rotor.angular_velocity, bodies[1]
    co_moving.velocity = (-w * co_moving.position.y, w * co_moving.position.x)  # exactly
    dt = units.to_internal(spec.granule_dt, units.TIME)
    expected, removed, supplied, dragged = _per_granule(sim, dt)
    floor, drag = sim.machine.effects
    assert sim.kicks is not None
    sim.kicks.run(spec.granule_dt)  # s: the kicks are SI
    for body, v in zip(bodies, expected, strict=True):
        np.testing.assert_allclose(tuple(body.velocity), tuple(v), rtol=1e-14, atol=1e-300)
    assert tuple(bodies[0].velocity) == tuple(expected[0])  # stopped on the floor
    assert floor.removed == pytest.approx(removed * units.ENERGY, rel=1e-14)
    assert floor.supplied == pytest.approx(supplied * units.ENERGY, rel=1e-14)
    assert drag.removed == pytest.approx(dragged * units.ENERGY, rel=1e-14)
    assert floor.removed > 0 and drag.removed > 0 and floor.supplied != 0


def test_air_drag_closed_form() -> None:
    """A granule coasting at 10 m/s in still air: dv/dt = −k v², v(t) = v0/(1 + k v0 t) exactly
    at every step (the kick integrates the step exactly; measured 7e-16), x(t) = ln(1 + k v0 t)/k
    to first order in dt (measured −4.4e-5 at dt = 1e-4 s), and the drag removed exactly the
    kinetic energy lost (measured 1e-15)."""
    rho, cd, th, r, m, v0, duration = 1.2, 1.0, 0.002, 0.002, 50e-6, 10.0, 0.2
    k = 0.5 * rho * cd * 2 * r * th / m
    granule = GranuleSpec(position=(0.0, 0.0), velocity=(v0, 0.0), radius=r, mass=m,
                          material="bb")  # fmt: skip
    spec = System(
        rotor=RotorSpec(angular_velocity=0.0, radius=0.2), hammers=(), granules=(granule,),
        contacts=(), granule_dt=1e-4, effects=EffectsSpec(air_drag=AirDragSpec(rho, cd, th)),
    )  # fmt: skip
    sim = Simulation(spec)
    sim.run(duration)
    (v,) = sim.frame().granules.velocities
    (p,) = sim.frame().granules.positions
    assert v[1] == 0.0 and p[1] == 0.0
    assert v[0] == pytest.approx(v0 / (1 + k * v0 * duration), rel=1e-12)
    assert p[0] == pytest.approx(math.log1p(k * v0 * duration) / k, rel=1e-4)
    ledger = sim.energy()
    assert ledger.drag == pytest.approx(0.5 * m * (v0**2 - v[0] ** 2), rel=1e-12)
    assert abs(ledger.closure) < 1e-12


def test_chamber_wall_reflects_granules_and_ignores_hammers() -> None:
    """A granule flying radially out at 5 m/s rebounds from the chamber wall with e = 0.5
    (exact: one impulse on a static wall, aimed at a face's tangent point), and a
    hinged hammer reaching past the wall's radius moves exactly as on an open rotor."""
    wall = ChamberSpec(radius=0.15, wall_thickness=0.02, material="wall", segments=96)
    c, s = math.cos(2 * math.pi / 96), math.sin(2 * math.pi / 96)  # a face middle (2πi/96)
    granule = GranuleSpec(position=(0.14 * c, 0.14 * s), velocity=(5.0 * c, 5.0 * s),
                          radius=0.002, mass=50e-6, material="bb")  # fmt: skip
    hammer = plate(0.0, 0.1, -0.01, 0.01, 0.05, hinge_radius=0.1, angle_on_rotor=2.0,
                   mount="hinged", material="steel")  # fmt: skip
    runs = []
    for chamber in (wall, None):
        spec = System(
            rotor=RotorSpec(angular_velocity=50.0, radius=0.12),
            hammers=(hammer,),
            granules=(granule,),
            contacts=(ContactSpec("bb", "steel", 0.5, 0.0),)
            + ((ContactSpec("bb", "wall", 0.5, 0.0),) if chamber else ()),
            granule_dt=1e-5,
            chamber=chamber,
        )
        runs.append(Simulation(spec))
        runs[-1].run(4e-3)
    sim, open_rotor = runs
    v = sim.frame().granules.velocities[0]
    assert v[0] * c + v[1] * s == pytest.approx(-2.5, rel=1e-12)
    assert sim.energy().contact_dissipation == pytest.approx(0.5 * 50e-6 * (25 - 6.25), rel=1e-9)
    # the hammer moves exactly as without the wall
    assert (
        sim.frame().machine.swing_angles.tolist()
        == open_rotor.frame().machine.swing_angles.tolist()
    )
    assert len(sim.contacts.bodies.wall_shapes) == 96


def test_chamber_pair_needs_contact_parameters() -> None:
    granule = GranuleSpec(position=(0.1, 0.0), velocity=(0, 0), radius=0.002, mass=1e-5,
                          material="bb")  # fmt: skip
    with pytest.raises(ValueError, match=r"no contact parameters for materials \['bb', 'wall'\]"):
        System(RotorSpec(10.0, 0.2), (), (granule,), (), granule_dt=1e-5,
                  chamber=ChamberSpec(0.25, 0.02, "wall"))  # fmt: skip
