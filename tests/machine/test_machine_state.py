"""The machine's state read raw from the bodies' structs (Machine.state), the loads written
back the same way (machine.write_loads), and the constraint effects' losses booked from two
states instead of Chipmunk callbacks (effects.ConstraintLosses)."""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest

from perga.engine import Simulation
from perga.machine.batch import BodyReader
from perga.machine.chipmunk_state import JointImpulses
from perga.machine.effects import ConstraintLosses, HingeFriction, SwingStops
from perga.machine.machine import write_loads
from perga.model import DriveSpec, EffectsSpec, RotorSpec, System
from tests.engine.helpers import plate


def _sim(effects: EffectsSpec, gravity: tuple[float, float] = (0.0, 0.0)) -> Simulation:
    """Two hinged hammers (one with stops), one welded and one free, on a slow rotor."""

    def bar(mount: str, phi: float, **kwargs: object) -> object:
        return plate(
            -0.005, 0.06, -0.01, 0.01, 0.03,
            hinge_radius=0.05, angle_on_rotor=phi, mount=mount, material="steel", **kwargs,
        )  # fmt: skip

    hammers = (
        bar("hinged", 1.5),
        bar("hinged", 0.0, swing_limit=0.3),
        bar("welded", 3.0),
        bar("free", 4.5, velocity=(0.3, -0.2), angular_velocity=2.0),
    )
    spec = System(
        rotor=RotorSpec(2.0, 0.12),
        hammers=hammers,
        granules=(),
        contacts=(),
        granule_dt=1e-4,
        gravity=gravity,
        effects=effects,
    )
    return Simulation(spec, record_impacts=False)


def test_state_rows_are_the_bodies() -> None:
    """Row 0 the rotor, then each hammer body that is not the rotor; angles, velocities and
    angular velocities exactly the bodies' (the same floats), centres of gravity to 4 ulp of a
    100 mm coordinate, the scene's scale (x + R·cog here, Chipmunk's transform there: the same
    terms rounded in another order; a cog left out or turned wrong is off by millimetres)."""
    sim = _sim(EffectsSpec(drive=DriveSpec(inertia=0.01, torque_limit=0.1)), (0.0, -9.80665))
    sim.run(0.05)
    machine = sim.machine
    state = machine.state()
    bodies = machine.bodies
    assert bodies[0] is machine.rotor and len(bodies) == 4  # the welded hammer is the rotor
    assert machine.hammer_rows.tolist() == [1, 2, 0, 3]
    for k, body in enumerate(bodies):
        centre = body.local_to_world(body.center_of_gravity)
        assert state.angle[k] == body.angle
        assert tuple(state.velocity[k]) == tuple(body.velocity)
        assert state.omega[k] == body.angular_velocity
        lever = max(abs(body.center_of_gravity.x), abs(body.center_of_gravity.y), 1.0)
        assert np.abs(state.centre[k] - tuple(centre)).max() <= 4 * np.spacing(100.0 * lever)


def _batch_table(reader: BodyReader, bodies: list[pymunk.Body]) -> np.ndarray:
    """The machine's table as the batch read made it before the raw read: ``pymunk.batch``'s
    positions, angles and velocities, the centre of gravity added as x + (c·cx − s·cy)."""
    ids, rows = reader.read_internal_space()
    out = rows[[int(np.flatnonzero(ids == b.id)[0]) for b in bodies]]
    for j, (cx, cy) in enumerate(tuple(b.center_of_gravity) for b in bodies):
        c, s = math.cos(out[j, 2]), math.sin(out[j, 2])
        out[j, 0] += c * cx - s * cy
        out[j, 1] += s * cx + c * cy
    return out


def test_the_raw_read_gives_the_batch_reads_floats() -> None:
    """Over a run of swinging hinged hammers, a driven rotor and a free hammer, every row of the
    state read raw equals, bit for bit, ``pymunk.batch``'s read of the same bodies with the
    centre of gravity added (the read it replaced): the bundled runs' tables stay the same."""
    sim = _sim(EffectsSpec(drive=DriveSpec(inertia=0.01, torque_limit=0.1)), (0.0, -9.80665))
    machine = sim.machine
    bodies = machine.bodies
    batch = BodyReader(machine.space, bodies)
    for _ in range(200):
        sim.step()
        table = machine.state().table
        assert np.array_equal(table, _batch_table(batch, bodies))
    assert np.ptp(table[1:, 2]) > 0.1  # the hammers turned apart


def test_loads_land_on_the_bodies_and_nowhere_else() -> None:
    sim = _sim(EffectsSpec())
    stranger = pymunk.Body(1.0, 1.0)
    sim.machine.space.add(stranger)
    stranger.force, stranger.torque = (7.0, 8.0), 9.0
    loads = np.arange(12.0).reshape(4, 3) + 1.0
    write_loads(sim.machine.body_addresses(), loads)
    for body, row in zip(sim.machine.bodies, loads, strict=True):
        assert (*body.force, body.torque) == tuple(row)
    assert (*stranger.force, stranger.torque) == (7.0, 8.0, 9.0)


class _Callbacks:
    """The losses as Chipmunk's constraint callbacks see them (the former implementation):
    −j·(mean of the relative angular velocity in pre_solve and post_solve), j the signed
    impulse on b, summed."""

    def __init__(self, constraints: list[pymunk.Constraint]) -> None:
        self.removed = 0.0
        self._before: dict[pymunk.Constraint, float] = {}
        for c in constraints:
            c.pre_solve = self._pre
            c.post_solve = self._post

    @staticmethod
    def _relative(c: pymunk.Constraint) -> float:
        return c.b.angular_velocity - c.a.angular_velocity

    def _pre(self, c: pymunk.Constraint, _space: pymunk.Space) -> None:
        self._before[c] = self._relative(c)

    def _post(self, c: pymunk.Constraint, _space: pymunk.Space) -> None:
        (j,) = JointImpulses([c]).read()  # signed; pymunk's impulse is |j|
        self.removed -= j * 0.5 * (self._before[c] + self._relative(c))


@pytest.mark.parametrize("kind", [HingeFriction, SwingStops])
def test_constraint_losses_equal_what_the_solver_callbacks_see(kind: type) -> None:
    """Hinge friction (slipping then sticking hinges) and a stop the hammer swings into under
    gravity: the losses booked from the states before and after each step equal, to rounding
    of the sum, what pre_solve/post_solve measure on the same constraints."""
    sim = _sim(EffectsSpec(hinge_friction=2e-3), (0.0, -9.80665))
    (effect,) = [e for e in sim.machine.effects if isinstance(e, kind)]
    assert isinstance(effect, ConstraintLosses)
    constraints = [c for c, _, _ in effect._watched]
    reference = _Callbacks(constraints)
    sim.run(0.2)
    assert reference.removed > 0.0
    assert effect._energy[0] == pytest.approx(reference.removed, rel=1e-12, abs=0.0)


def test_the_chipmunk_step_carries_no_python_callback() -> None:
    """Hinge friction and stops with the ledger on: no constraint has a solver callback (their
    losses come from the states, :class:`ConstraintLosses`)."""
    sim = _sim(EffectsSpec(hinge_friction=2e-3))
    assert len(sim.machine.space.constraints) == 5  # 2 hinges, 2 friction motors, 1 stop
    for c in sim.machine.space.constraints:
        assert c.pre_solve is None and c.post_solve is None


def test_a_hammers_state_from_the_read_state_is_pymunks() -> None:
    """A hammer's state taken from the machine's read state (hinged and free hammers; a welded
    one asks pymunk either way) equals the one from its pymunk body, the same floats, at every
    one of 40 instants of a driven rotor under gravity with a hammer on its stops (pymunk's
    velocity at the centre of gravity is the body's own v)."""
    sim = _sim(EffectsSpec(drive=DriveSpec(inertia=0.01, torque_limit=0.1)), (0.0, -9.80665))
    machine = sim.machine
    for _ in range(40):
        sim.run(0.002)
        state = machine.state()
        for index in range(len(machine.spec.hammers)):
            assert machine.hammer_state(index, state) == machine.hammer_state(index)
