"""Effects are built only when listed (design §3), and the chamber wall."""

from __future__ import annotations

import math

import pymunk
import pytest

from perga.engine import (
    AirDragSpec,
    ChamberSpec,
    ContactSpec,
    DriveSpec,
    EffectsSpec,
    FloorFrictionSpec,
    GranuleSpec,
    RotorSpec,
    Scene,
    SceneSpec,
    Simulation,
    build_scene,
)
from tests.engine.helpers import plate

EFFECTS = {
    "floor_friction": FloorFrictionSpec("corotating", 0.3),
    "air_drag": AirDragSpec(air_density=1.2, drag_coefficient=1.0, thickness=0.002),
    "hinge_friction": 0.05,
    "drive": DriveSpec(inertia=0.05, torque_limit=5.0),
}


def _scene(**effects: object) -> Scene:
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
    spec = SceneSpec(
        rotor=RotorSpec(omega=50.0, radius=0.2),
        hammers=hammers,
        granules=granules,
        contacts=(ContactSpec("bb", "steel", 0.5, 0.3), ContactSpec("bb", "wall", 0.5, 0.3)),
        dt=1e-5,
        chamber=ChamberSpec(radius=0.25, wall_thickness=0.02, material="wall"),
        effects=EffectsSpec(**effects),  # type: ignore[arg-type]
    )
    return build_scene(spec)


def _trace(scene: Scene) -> dict[str, object]:
    """Everything an effect could leave in the space."""
    return {
        "handlers": sorted(scene._listeners),
        "callbacks": sum(len(v) for v in scene._listeners.values()),
        "constraints": len(scene.space.constraints),
        "constraint_hooks": [(c.pre_solve, c.post_solve) for c in scene.space.constraints],
        "velocity_funcs": [
            b.velocity_func is pymunk.Body.update_velocity for b in scene.space.bodies
        ],
        "rotor_type": scene.rotor.body_type,
        "effects": len(scene.effects),
    }


def test_no_effect_leaves_no_trace() -> None:
    bare = _trace(_scene())
    assert bare["constraints"] == 1  # the hinge's pivot only
    assert bare["constraint_hooks"] == [(None, None)]
    assert all(bare["velocity_funcs"])
    assert bare["rotor_type"] == pymunk.Body.KINEMATIC
    assert bare["effects"] == 0


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_each_effect_installs_only_itself(name: str) -> None:
    """Listing one effect changes exactly what that effect is made of, and no handler."""
    bare, one = _trace(_scene()), _trace(_scene(**{name: EFFECTS[name]}))
    changed = {key for key in bare if bare[key] != one[key]}
    expected = {
        "floor_friction": {"velocity_funcs", "effects"},
        "air_drag": {"velocity_funcs", "effects"},
        "hinge_friction": {"constraints", "constraint_hooks", "effects"},
        "drive": {"constraints", "constraint_hooks", "rotor_type", "effects"},
    }[name]
    assert changed == expected
    if "velocity_funcs" in changed:  # the granules' functions, not the hammers'
        scene = _scene(**{name: EFFECTS[name]})
        kicked = {
            b for b in scene.space.bodies if b.velocity_func is not pymunk.Body.update_velocity
        }
        assert kicked == set(scene.granule_bodies)


def test_chamber_wall_reflects_granules_and_ignores_hammers() -> None:
    """A granule flying radially out at 5 m/s rebounds from the chamber wall with e = 0.5
    (exact: one impulse on a static wall, aimed at a face's tangent point), and a
    hinged hammer reaching past the wall's radius moves exactly as on an open rotor."""
    wall = ChamberSpec(radius=0.15, wall_thickness=0.02, material="wall", segments=96)
    c, s = math.cos(math.pi / 96), math.sin(math.pi / 96)  # a face's tangent point
    granule = GranuleSpec(position=(0.14 * c, 0.14 * s), velocity=(5.0 * c, 5.0 * s),
                          radius=0.002, mass=50e-6, material="bb")  # fmt: skip
    hammer = plate(0.0, 0.1, -0.01, 0.01, 0.05, hinge_radius=0.1, angle_on_rotor=2.0,
                   mount="hinged", material="steel")  # fmt: skip
    runs = []
    for chamber in (wall, None):
        spec = SceneSpec(
            rotor=RotorSpec(omega=50.0, radius=0.12),
            hammers=(hammer,),
            granules=(granule,),
            contacts=(ContactSpec("bb", "steel", 0.5, 0.0),)
            + ((ContactSpec("bb", "wall", 0.5, 0.0),) if chamber else ()),
            dt=1e-5,
            chamber=chamber,
        )
        runs.append(Simulation(build_scene(spec)))
        runs[-1].run(4e-3)
    sim, open_rotor = runs
    v = sim.granule_velocities()[0]
    assert v[0] * c + v[1] * s == pytest.approx(-2.5, rel=1e-12)
    assert sim.energy().contact_dissipation == pytest.approx(0.5 * 50e-6 * (25 - 6.25), rel=1e-9)
    # the hammer moves exactly as without the wall
    assert sim.hammer_swing_angles().tolist() == open_rotor.hammer_swing_angles().tolist()
    assert len(sim.scene.wall_shapes) == 96


def test_chamber_pair_needs_contact_parameters() -> None:
    granule = GranuleSpec(position=(0.1, 0.0), velocity=(0, 0), radius=0.002, mass=1e-5,
                          material="bb")  # fmt: skip
    with pytest.raises(ValueError, match=r"no contact parameters for materials \['bb', 'wall'\]"):
        SceneSpec(RotorSpec(10.0, 0.2), (), (granule,), (), dt=1e-5,
                  chamber=ChamberSpec(0.25, 0.02, "wall"))  # fmt: skip
