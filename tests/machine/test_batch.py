"""Batch state reads and velocity writes (perga.machine.batch) against per-body reads and
writes in a Python loop.

Tolerance: exact. The reader multiplies the very float64 values Chipmunk holds by the same unit
factor as the reference, so any difference would be a wrong row or column, not rounding; the
writer writes float64 values and every other body's own bits back.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pymunk
import pytest

from perga.contact.rigid.bodies import RigidBodies, attach_bodies
from perga.engine import Simulation
from perga.machine import batch as state_module
from perga.machine import units as u
from perga.machine.batch import BodyReader, BodyWriter
from perga.machine.machine import build_machine
from perga.model import ContactSpec, GranuleSpec, HammerSpec, RotorSpec, System
from tests.engine.helpers import plate

OMEGA = 150.0  # rad/s: hammer tips at ~20 m/s
RADIUS = 1.5e-3  # m


def _parts(bodies: RigidBodies) -> tuple:
    """A reader's or writer's arguments: the space and its granule bodies."""
    return bodies.space, bodies.granule_bodies


def _spec(n_rings: int = 3) -> System:
    """Kinematic rotor; four hinged, one welded and one free hammer; a ring of rolling and
    sliding granules in the hammers' sweep, granule collisions on."""

    def bar(x0: float, x1: float, mass: float, **kwargs: object) -> HammerSpec:
        return plate(x0, x1, -0.003, 0.003, mass, material="steel", **kwargs)

    hammers = [
        bar(0.0, 0.06, 0.05, hinge_radius=0.08, angle_on_rotor=k * math.pi / 3, mount="hinged")
        for k in range(4)
    ]
    hammers.append(
        bar(0.0, 0.05, 0.05, hinge_radius=0.08, angle_on_rotor=4 * math.pi / 3, mount="welded")
    )
    free = {"velocity": (-5.0, 1.0), "angular_velocity": 3.0}
    hammers.append(
        bar(-0.01, 0.01, 0.02, hinge_radius=0.3, angle_on_rotor=0.0, mount="free", **free)
    )
    granules = []
    for ring in range(n_rings):
        radius = 0.10 + 0.004 * ring
        count = int(2 * math.pi * radius / (2.6 * RADIUS))
        for k in range(count):
            phi = 2 * math.pi * (k + 0.5 * ring) / count
            gap = min(
                abs((phi - j * math.pi / 3 + math.pi) % (2 * math.pi) - math.pi) for j in range(6)
            )
            if gap < 0.08:
                continue  # keep clear of the hammers' start positions
            granules.append(
                GranuleSpec(
                    position=(radius * math.cos(phi), radius * math.sin(phi)),
                    velocity=(0.3 * math.sin(3 * phi), -0.2 * math.cos(phi)),
                    radius=RADIUS,
                    mass=5e-6,
                    material="bb",
                    rolls=k % 3 != 0,
                    angular_velocity=OMEGA if k % 3 == 0 else 10.0 * math.cos(phi),
                )
            )
    return System(
        rotor=RotorSpec(angular_velocity=OMEGA, radius=0.07),
        hammers=tuple(hammers),
        granules=tuple(granules),
        contacts=(
            ContactSpec("bb", "steel", restitution=0.6, friction=0.4),
            ContactSpec("bb", "bb", restitution=0.5, friction=0.3),
        ),
        granule_dt=2e-5,
        granule_collisions=True,
    )


class Kinematics(NamedTuple):
    """What a reader reads, SI: positions (n, 2), velocities (n, 2), angular velocities (n,)."""

    positions: np.ndarray
    velocities: np.ndarray
    angular_velocities: np.ndarray


def _loop(sim: Simulation) -> Kinematics:
    """Reference: every granule body's attributes read one by one."""
    bodies = sim.contacts.bodies.granule_bodies
    return Kinematics(
        positions=np.array([tuple(b.position) for b in bodies], dtype=float) * u.LENGTH,
        velocities=np.array([tuple(b.velocity) for b in bodies], dtype=float) * u.VELOCITY,
        angular_velocities=np.array([b.angular_velocity for b in bodies], dtype=float)
        * u.ANGULAR_VELOCITY,
    )


def _assert_same(got: tuple, expected: Kinematics) -> None:
    for name in ("positions", "velocities", "angular_velocities"):
        a, b = getattr(got, name), getattr(expected, name)
        assert a.shape == b.shape and a.dtype == np.float64, name
        assert np.all(np.isfinite(a)), name
        np.testing.assert_array_equal(a, b, err_msg=name)


@pytest.fixture(scope="module")
def stepped() -> Simulation:
    """The scene after 3 ms (hammers have hit granules, granules hit each other)."""
    sim = Simulation(_spec())
    sim.run(3e-3)
    return sim


def test_scene_is_a_real_test(stepped: Simulation) -> None:
    # the reads below mean something only if bodies of every kind are in the space and the
    # granules have been struck: kinematic rotor, dynamic hammers, many granules in motion
    kinds = {b.body_type for b in stepped.contacts.bodies.space.bodies}
    assert kinds == {pymunk.Body.KINEMATIC, pymunk.Body.DYNAMIC}
    assert len(stepped.impacts) > 5
    speeds = np.linalg.norm(_loop(stepped).velocities, axis=1)
    assert speeds.max() > 5.0


def test_matches_python_loop_exactly(stepped: Simulation) -> None:
    reader = BodyReader(*_parts(stepped.contacts.bodies))
    expected = _loop(stepped)
    _assert_same(Kinematics(*reader.read()), expected)
    np.testing.assert_array_equal(reader.positions(), expected.positions)
    np.testing.assert_array_equal(reader.velocities(), expected.velocities)
    np.testing.assert_array_equal(reader.angular_velocities(), expected.angular_velocities)
    _assert_same(Kinematics(*BodyReader(*_parts(stepped.contacts.bodies)).read()), expected)


def test_matches_loop_while_stepping() -> None:
    sim = Simulation(_spec(n_rings=2))
    reader = BodyReader(*_parts(sim.contacts.bodies))
    for _ in range(5):
        sim.run(4e-4)
        _assert_same(Kinematics(*reader.read()), _loop(sim))


def test_rows_are_in_spec_order() -> None:
    spec = _spec(n_rings=2)
    reader = BodyReader(*_parts(attach_bodies(build_machine(spec))))
    state = Kinematics(*reader.read())
    assert reader.count == len(spec.granules) == state.positions.shape[0]
    for i, g in enumerate(spec.granules):
        # SI -> mm -> SI: x / 1e-3 * 1e-3 is within 1 ulp of x
        for got, want in zip(state.positions[i], g.position, strict=True):
            assert abs(got - want) <= np.spacing(abs(want))
        for got, want in zip(state.velocities[i], g.velocity, strict=True):
            assert got == want  # the velocity unit is 1 (m/s = mm/ms)
        assert abs(state.angular_velocities[i] - g.angular_velocity) <= np.spacing(
            abs(g.angular_velocity)
        )


def test_survives_reordering_of_chipmunks_body_array() -> None:
    sim = Simulation(_spec(n_rings=2))
    reader = BodyReader(*_parts(sim.contacts.bodies))
    sim.run(2e-4)
    _assert_same(Kinematics(*reader.read()), _loop(sim))
    # removing a body moves Chipmunk's last body into its slot; Pymunk creates and adds
    # space.static_body on first access: both change the rows of the batch read (the machine
    # then lacks a hammer, so the space is stepped on its own)
    rows = reader._rows.copy()
    free = sim.machine.hammer_bodies[-1]
    sim.machine.space.remove(free, *free.shapes)
    assert sim.machine.space.static_body is not None
    for _ in range(4):
        sim.machine.space.step(u.to_internal(sim.dt, u.TIME))
    _assert_same(Kinematics(*reader.read()), _loop(sim))
    assert not np.array_equal(reader._rows, rows)  # the rows did move


def test_reads_stay_exact_when_the_buffer_grows() -> None:
    """The reader's numpy views of the batch buffer's C arrays are made again when a fetch
    reallocates them: after bodies are added (the arrays grow), a read is still the loop's."""
    sim = Simulation(_spec(n_rings=1))
    reader = BodyReader(*_parts(sim.contacts.bodies))
    _assert_same(Kinematics(*reader.read()), _loop(sim))
    pointers = reader._buffer._pointers
    space = sim.machine.space
    for k in range(4 * len(space.bodies)):
        extra = pymunk.Body(1.0, 1.0)
        extra.position = (float(k), -1.0)
        space.add(extra)
    sim.run(2e-4)
    _assert_same(Kinematics(*reader.read()), _loop(sim))
    assert reader._buffer._pointers != pointers  # the arrays were reallocated


def test_granule_missing_from_space_is_an_error() -> None:
    scene = attach_bodies(build_machine(_spec(n_rings=1)))
    reader = BodyReader(*_parts(scene))
    body = scene.granule_bodies[3]
    scene.space.remove(body, *body.shapes)
    with pytest.raises(LookupError, match=r"bodies \[3\]"):
        reader.positions()


def test_short_float_buffer_is_an_error(monkeypatch: pytest.MonkeyPatch) -> None:
    scene = attach_bodies(build_machine(_spec(n_rings=1)))
    reader = BodyReader(*_parts(scene))
    real = state_module._BatchBuffer.get

    def short(self: object, space: pymunk.Space, fields: object) -> tuple:
        ids, floats = real(self, space, fields)
        return ids, floats[:-1]  # one float missing, as a changed layout would give

    monkeypatch.setattr(state_module._BatchBuffer, "get", short)
    with pytest.raises(RuntimeError, match="expected 2 per body"):
        reader.positions()


def _empty() -> System:
    """A rotor alone: no hammers, no granules."""
    return System(
        rotor=RotorSpec(angular_velocity=10.0, radius=0.1),
        hammers=(),
        granules=(),
        contacts=(),
        granule_dt=1e-5,
    )


def test_no_granules() -> None:
    spec = _empty()
    state = Kinematics(*BodyReader(*_parts(attach_bodies(build_machine(spec)))).read())
    assert state.positions.shape == (0, 2)
    assert state.velocities.shape == (0, 2)
    assert state.angular_velocities.shape == (0,)


# --- the writer ------------------------------------------------------------------------------


def _everything(scene: RigidBodies) -> list[tuple[float, ...]]:
    """Every body's (static body included) position, angle, velocity and angular velocity."""
    bodies = [*scene.space.bodies, scene.space.static_body]
    return [(*b.position, b.angle, *b.velocity, b.angular_velocity) for b in bodies]


def _others(scene: RigidBodies) -> list[tuple[float, ...]]:
    granules = set(scene.granule_bodies)
    bodies = [b for b in scene.space.bodies if b not in granules] + [scene.space.static_body]
    return [(*b.position, b.angle, *b.velocity, b.angular_velocity) for b in bodies]


def test_writer_sets_granule_velocities_only(stepped: Simulation) -> None:
    scene = stepped.contacts.bodies
    writer = BodyWriter(*_parts(scene))  # its construction check writes and undoes: nothing changes
    before, others = _loop(stepped), _others(scene)
    _assert_same(Kinematics(*writer.read()), before)
    v, p = writer.read_internal(positions=True)
    assert p is not None
    np.testing.assert_array_equal(p * u.LENGTH, before.positions)
    np.testing.assert_array_equal(v * u.VELOCITY, before.velocities)
    assert writer.read_internal(positions=False)[1] is None

    rng = np.random.default_rng(3)
    new = rng.normal(scale=7.0, size=v.shape)
    writer.write_internal_velocities(new)
    got = np.array([tuple(b.velocity) for b in scene.granule_bodies])
    np.testing.assert_array_equal(got, new)  # bit for bit, in spec order
    after = _loop(stepped)
    np.testing.assert_array_equal(after.positions, before.positions)
    np.testing.assert_array_equal(after.angular_velocities, before.angular_velocities)
    assert _others(scene) == others  # rotor, hammers, static body: every field unchanged
    writer.write_internal_velocities(v)  # restore the module fixture
    _assert_same(_loop(stepped), before)


def test_writer_survives_reordering() -> None:
    sim = Simulation(_spec(n_rings=2))
    writer = BodyWriter(*_parts(sim.contacts.bodies))
    free = sim.machine.hammer_bodies[-1]
    sim.machine.space.remove(free, *free.shapes)
    assert sim.machine.space.static_body is not None
    for _ in range(4):  # the machine lacks a hammer now: the space is stepped on its own
        sim.machine.space.step(u.to_internal(sim.dt, u.TIME))
    others = _others(sim.contacts.bodies)
    new = np.arange(2.0 * writer.count).reshape(-1, 2)
    writer.write_internal_velocities(new)
    np.testing.assert_array_equal(
        [tuple(b.velocity) for b in sim.contacts.bodies.granule_bodies], new
    )
    assert _others(sim.contacts.bodies) == others


def test_writer_rejects_bad_velocities() -> None:
    scene = attach_bodies(build_machine(_spec(n_rings=1)))
    writer = BodyWriter(*_parts(scene))
    before = _everything(scene)
    v, _ = writer.read_internal(positions=False)
    with pytest.raises(ValueError, match="shape"):
        writer.write_internal_velocities(v[:-1])
    with pytest.raises(ValueError, match="shape"):
        writer.write_internal_velocities(v.ravel())
    v[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"non-finite velocities for bodies \[2\]"):
        writer.write_internal_velocities(v)
    assert _everything(scene) == before


def test_writer_granule_missing_from_space_is_an_error() -> None:
    scene = attach_bodies(build_machine(_spec(n_rings=1)))
    writer = BodyWriter(*_parts(scene))
    v, _ = writer.read_internal(positions=False)
    body = scene.granule_bodies[3]
    scene.space.remove(body, *body.shapes)
    before = _everything(scene)
    with pytest.raises(LookupError, match=r"bodies \[3\]"):
        writer.write_internal_velocities(v)
    assert _everything(scene) == before


def test_writer_short_buffer_is_an_error(monkeypatch: pytest.MonkeyPatch) -> None:
    scene = attach_bodies(build_machine(_spec(n_rings=1)))
    writer = BodyWriter(*_parts(scene))
    v, _ = writer.read_internal(positions=False)
    real = state_module._BatchBuffer.get

    def short(self: object, space: pymunk.Space, fields: object) -> tuple:
        ids, floats = real(self, space, fields)
        return ids, floats[:-1]

    monkeypatch.setattr(state_module._BatchBuffer, "get", short)
    before = _everything(scene)
    with pytest.raises(RuntimeError, match="expected 2 per body"):
        writer.write_internal_velocities(v)
    assert _everything(scene) == before


@pytest.mark.parametrize("fault", ["no-op", "shifted"])
def test_writer_checks_the_write_layout(monkeypatch: pytest.MonkeyPatch, fault: str) -> None:
    """A set_space_bodies that writes nothing, or writes every body's row one body later (as a
    changed layout would), fails the writer's construction check."""
    scene = attach_bodies(build_machine(_spec(n_rings=1)))
    real = state_module._BatchBuffer.set

    def faulty(self: state_module._BatchBuffer, space: pymunk.Space, fields: object) -> None:
        if fault == "shifted":
            floats = np.frombuffer(self.buffer.float_buf(), dtype=np.float64)
            floats[:] = np.roll(floats, 2)
            real(self, space, fields)

    monkeypatch.setattr(state_module._BatchBuffer, "set", faulty)
    with pytest.raises(RuntimeError, match="set_space_bodies check failed"):
        BodyWriter(*_parts(scene))


def test_writer_no_granules() -> None:
    spec = _empty()
    scene = attach_bodies(build_machine(spec))
    writer = BodyWriter(*_parts(scene))
    v, p = writer.read_internal(positions=True)
    assert v.shape == (0, 2) and p is not None and p.shape == (0, 2)
    writer.write_internal_velocities(np.zeros((0, 2)))
