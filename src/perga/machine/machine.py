"""System -> Machine: the rotor, the hammers and their joints as Pymunk bodies, and the
effects the spec lists. The only place the machine's Pymunk objects are made; the granules and
the chamber wall belong to the contact model (:mod:`perga.contact`), which adds what it needs.

Construction (all quantities converted to the internal units of :mod:`perga.machine.units`):

* Rotor: a kinematic body at the origin with ``angular_velocity = ω``; it carries no shapes of
  its own (a rotor disc is out of the granules' plane).
* Hammers, by mount; each convex piece of the hammer's outline (``HammerSpec.pieces``) is one
  ``Poly`` on the hammer's body, in the hammers' filter group (hammers never collide with each
  other, with the rotor or with the chamber wall):

  - ``hinged``: a dynamic body whose local origin is the hinge, with mass, centre of gravity
    and the moment about the centre of mass I_C = I_A − M|c|² from the spec, pinned to the
    rotor by a ``PivotJoint`` at the hinge. It starts co-rotating with the rotor. With
    ``swing_limit`` a ``RotaryLimitJoint`` to the rotor stops it at α = ±swing_limit.
  - ``welded``: the hammer's polygons are attached to the rotor body itself (its outline
    transformed into the rotor frame). At constant ω this is exactly rigid (no joint error,
    no solver iterations), and the hammer's mass properties are irrelevant because the
    kinematic rotor has infinite inertia (a driven rotor adds them: :class:`~perga.engine.
    effects.Drive`).
  - ``free``: a dynamic body with no attachment, starting with the spec's velocity (for
    validation scenes such as a free two-body impact).

* Effects: :mod:`perga.machine.effects` builds exactly the effects the spec lists, after the
  hammers (the drive turns the rotor into a dynamic body).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numba
import numpy as np
import pymunk
from numpy.typing import NDArray

from perga.machine import units as u
from perga.machine.chipmunk_state import (
    VIEW_ANGLE,
    VIEW_F,
    VIEW_P,
    VIEW_T,
    VIEW_TRANSFORM,
    VIEW_V,
    VIEW_W,
    VIEW_WIDTH,
    BodyViews,
    capture,
    doubles_at,
    raw_space_step,
    restore,
    space_step,
)
from perga.machine.effects import Effect, SwingStops, build_effects
from perga.model.frame import MachineFrame, frozen
from perga.model.records import HammerState
from perga.model.system import HammerSpec, System, Vec2

HAMMER_GROUP = 1
"""Shape filter group of the hammers and the chamber wall: they never collide with each other."""

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MachineState:
    """The machine's bodies at one instant (:attr:`Machine.bodies`: row 0 the rotor, then the
    hammer bodies that are not the rotor), internal units (:mod:`perga.machine.units`), read raw
    from their C structs (:class:`~perga.machine.chipmunk_state.BodyViews`): ``table`` (k, 6),
    per body x, y (its centre of gravity in the world), angle, vx, vy (velocity of the centre
    of gravity), ω. Compiled code takes the table."""

    table: FloatArray

    @property
    def centre(self) -> FloatArray:
        """Centres of gravity, (k, 2)."""
        return self.table[:, 0:2]

    @property
    def angle(self) -> FloatArray:
        """Angles, (k,)."""
        return self.table[:, 2]

    @property
    def velocity(self) -> FloatArray:
        """Velocities of the centres of gravity, (k, 2)."""
        return self.table[:, 3:5]

    @property
    def omega(self) -> FloatArray:
        """Angular velocities, (k,)."""
        return self.table[:, 5]


@dataclass
class Machine:
    """The Pymunk objects of the machine.

    ``hammer_bodies[i]`` is the rotor body for a welded hammer; ``hammer_shapes[i]`` are hammer
    i's convex pieces, ``hammer_outlines[i]`` its whole outline in its body's frame (internal
    units); ``hinges`` the hinged hammers' pivot joints; ``effects`` the effects built
    (:mod:`perga.machine.effects`), in build order.
    """

    spec: System
    space: pymunk.Space
    rotor: pymunk.Body
    hammer_bodies: list[pymunk.Body]
    hammer_shapes: list[tuple[pymunk.Poly, ...]]
    hammer_outlines: list[list[tuple[float, float]]]
    hinges: list[pymunk.PivotJoint]
    effects: list[Effect] = field(default_factory=list)
    _raw: BodyViews | None = field(default=None, repr=False)
    _hammer_rows: NDArray[np.int64] | None = field(default=None, repr=False)
    _cogs: FloatArray = field(default_factory=lambda: np.zeros((0, 2)), repr=False)

    def __getstate__(self) -> dict[str, object]:
        """The fields, with what pymunk's pickle of the space misses
        (:func:`~perga.machine.chipmunk_state.capture`): a copy or a pickle round trip steps as
        the original does."""
        return {**self.__dict__, "_chipmunk": capture(self.space)}

    def __setstate__(self, state: dict[str, Any]) -> None:
        fields = dict(state)
        chipmunk = fields.pop("_chipmunk")
        self.__dict__.update(fields)
        restore(self.space, chipmunk)

    @property
    def bodies(self) -> list[pymunk.Body]:
        """The rotor, then each hammer body that is not the rotor (rows of a
        :class:`MachineState`)."""
        return [self.rotor, *(b for b in self.hammer_bodies if b is not self.rotor)]

    def row_of(self, body: pymunk.Body) -> int:
        """``body``'s row in :attr:`bodies` and in a :class:`MachineState`."""
        return next(k for k, b in enumerate(self.bodies) if b is body)

    @property
    def hammer_rows(self) -> NDArray[np.int64]:
        """Each hammer's row in a :class:`MachineState` (0, the rotor, for a welded one)."""
        if self._hammer_rows is None:
            rows = np.array([self.row_of(b) for b in self.hammer_bodies], dtype=np.int64)
            rows.setflags(write=False)  # made once and shared: no caller may change it
            self._hammer_rows = rows
        return self._hammer_rows

    def state(self) -> MachineState:
        """The machine's bodies now (:class:`MachineState`), one compiled read of their structs."""
        addresses = self.body_addresses()
        table = np.empty((len(addresses), 6))
        read_bodies(addresses, self._cogs, table)
        return MachineState(table)

    def raw_step(self, dt: float) -> tuple | None:
        """The arguments of :func:`chipmunk_step` for steps of ``dt`` (internal time units):
        (cpSpaceStep's address, the space's, dt, :meth:`body_addresses`, the bodies' centres of
        gravity), or None while pymunk's ``Space.step`` has work of its own
        (:func:`~perga.machine.chipmunk_state.raw_space_step`). Take them afresh for each run of
        compiled steps: the addresses change with a checkpoint read back."""
        addresses = raw_space_step(self.space)
        if addresses is None:
            return None
        return (*addresses, float(dt), self.body_addresses(), self._cogs)

    def body_addresses(self) -> NDArray[np.uint64]:
        """The addresses of the raw structs of :attr:`bodies` (made at first use, when the
        space is complete, with their centres of gravity; made again after unpickling: take
        them at each use), for compiled code that reads them or sets their loads
        (:func:`write_loads`)."""
        if self._raw is None:
            bodies = self.bodies
            self._raw = BodyViews(bodies)
            self._cogs = np.array([tuple(b.center_of_gravity) for b in bodies], dtype=float)
        return self._raw.addresses()

    @property
    def driven(self) -> bool:
        """Whether the rotor is a dynamic body held at ω by a motor (the drive effect)."""
        return self.rotor.body_type == pymunk.Body.DYNAMIC

    def hammer_state(self, index: int, state: MachineState | None = None) -> HammerState:
        """The :class:`HammerState` of hammer ``index`` now; ``state``, the machine's state now
        if it has been read, gives that of a hammer with a body of its own (hinged or free)
        without asking pymunk: its velocity at the centre of gravity is its body's v, the same
        floats (``tests/machine/test_machine_state.py``)."""
        spec = self.spec.hammers[index]
        body = self.hammer_bodies[index]
        welded = body is self.rotor
        if state is not None and not welded:
            row = state.table[self.hammer_rows[index]]
            vx, vy = row[3] * u.VELOCITY, row[4] * u.VELOCITY
            spin = row[5] * u.ANGULAR_VELOCITY
            return HammerState(
                energy=float(
                    0.5 * spec.mass * (vx**2 + vy**2) + 0.5 * spec.moment_about_centre * spin**2
                ),
                swing_angle=float(row[2] - state.table[0, 2] - spec.angle_on_rotor),
                angular_velocity=float(spin),
                centre=(float(row[0] * u.LENGTH), float(row[1] * u.LENGTH)),
            )
        centre = (
            self._welded_centre(spec) if welded else body.local_to_world(body.center_of_gravity)
        )
        v = body.velocity_at_world_point(centre) * u.VELOCITY
        spin = body.angular_velocity * u.ANGULAR_VELOCITY
        return HammerState(
            energy=0.5 * spec.mass * v.length_squared + 0.5 * spec.moment_about_centre * spin**2,
            swing_angle=spec.swing_angle
            if welded
            else body.angle - self.rotor.angle - spec.angle_on_rotor,
            angular_velocity=spin,
            centre=u.vec_to_si(tuple(centre), u.LENGTH),
        )

    def frame(self, dt: float) -> MachineFrame:
        """Rotor and hammers now, SI (``dt``: the machine step, s, over which the hinge impulses
        act)."""
        hinges, axes, velocities = [], [], []
        for spec, body in zip(self.spec.hammers, self.hammer_bodies, strict=True):
            if body is self.rotor:
                hinge = body.local_to_world(u.vec_to_internal(spec.hinge_position, u.LENGTH))
                axes.append(body.angle + spec.angle_on_rotor + spec.swing_angle)
                velocities.append(tuple(body.velocity_at_world_point(self._welded_centre(spec))))
            else:
                hinge = body.position
                axes.append(body.angle)
                velocities.append(tuple(body.velocity))
            hinges.append(tuple(hinge))
        impulse = {j.b: j.impulse for j in self.hinges}
        states = [self.hammer_state(i) for i in range(len(self.spec.hammers))]
        return MachineFrame(
            rotor_angle=float(self.rotor.angle),
            rotor_angular_velocity=float(self.rotor.angular_velocity) * u.ANGULAR_VELOCITY,
            hinges=frozen(np.array(hinges, dtype=float).reshape(-1, 2) * u.LENGTH),
            axis_angles=frozen(np.array(axes, dtype=float)),
            swing_angles=frozen(np.array([s.swing_angle for s in states], dtype=float)),
            angular_velocities=frozen(np.array([s.angular_velocity for s in states], dtype=float)),
            velocities=frozen(np.array(velocities, dtype=float).reshape(-1, 2) * u.VELOCITY),
            hinge_forces=frozen(
                np.array([impulse.get(b, 0.0) for b in self.hammer_bodies], dtype=float)
                * u.IMPULSE
                / dt
            ),
        )

    def _welded_centre(self, spec: HammerSpec) -> pymunk.Vec2d:
        """World position (internal units) of a welded hammer's centre of mass."""
        return self.rotor.local_to_world(u.vec_to_internal(spec.centre_on_rotor, u.LENGTH))


@numba.njit(cache=True)
def read_bodies(addresses: NDArray[np.uint64], cogs: FloatArray, out: FloatArray) -> None:
    """Row j of ``out``: body j's centre of gravity in the world, angle, velocity and angular
    velocity from its raw struct at ``addresses[j]`` (:class:`MachineState`;
    :meth:`~perga.machine.chipmunk_state.BodyViews.addresses`). The body's position is
    its transform applied to the origin, as ``cpBodyGetPosition`` computes it, and the centre of
    gravity ``cogs[j]`` (body frame) is added turned by the angle: the same floats as pymunk's
    ``body.position`` + R(angle)·``center_of_gravity``."""
    for j in range(addresses.size):
        raw = doubles_at(addresses[j], VIEW_WIDTH)
        t = VIEW_TRANSFORM
        x = raw[t] * 0.0 + raw[t + 2] * 0.0 + raw[t + 4]
        y = raw[t + 1] * 0.0 + raw[t + 3] * 0.0 + raw[t + 5]
        angle = raw[VIEW_ANGLE]
        c, s = math.cos(angle), math.sin(angle)
        out[j, 0] = x + (c * cogs[j, 0] - s * cogs[j, 1])
        out[j, 1] = y + (s * cogs[j, 0] + c * cogs[j, 1])
        out[j, 2] = angle
        out[j, 3] = raw[VIEW_V]
        out[j, 4] = raw[VIEW_V + 1]
        out[j, 5] = raw[VIEW_W]


@numba.njit(cache=True)
def chipmunk_step(raw: tuple, out: FloatArray) -> None:
    """Chipmunk's step of the space, then the machine's state read into ``out`` (a
    :class:`MachineState` table), in compiled code; ``raw``: :meth:`Machine.raw_step`'s."""
    function, space, dt, addresses, cogs = raw
    space_step(function, space, dt)
    read_bodies(addresses, cogs, out)


@numba.njit(cache=True)
def write_loads(addresses: NDArray[np.uint64], loads: FloatArray) -> None:
    """Body j's force and torque (the f and t of its struct at ``addresses[j]``) from
    ``loads[j]`` = (fx, fy, torque)."""
    for j in range(addresses.size):
        raw = doubles_at(addresses[j], VIEW_WIDTH)
        raw[VIEW_F] = loads[j, 0]
        raw[VIEW_F + 1] = loads[j, 1]
        raw[VIEW_T] = loads[j, 2]


@numba.njit(cache=True)
def shift_bodies(addresses: NDArray[np.uint64], shifts: FloatArray) -> None:
    """Move body j's centre of gravity and angle (the p and a of its struct at
    ``addresses[j]``) by ``shifts[j]`` = (dx, dy, dangle), internal units, before a step:
    Chipmunk's step then drifts the body from there (its transform follows p and a)."""
    for j in range(addresses.size):
        if shifts[j, 0] == 0.0 and shifts[j, 1] == 0.0 and shifts[j, 2] == 0.0:
            continue
        raw = doubles_at(addresses[j], VIEW_WIDTH)
        raw[VIEW_P] += shifts[j, 0]
        raw[VIEW_P + 1] += shifts[j, 1]
        raw[VIEW_ANGLE] += shifts[j, 2]


def _rotate(x: float, y: float, angle: float) -> tuple[float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return (c * x - s * y, s * x + c * y)


def build_machine(spec: System) -> Machine:
    """Build the Pymunk space of rotor and hammers for ``spec``, with its effects (module doc)."""
    space = pymunk.Space()
    space.iterations = spec.iterations
    space.gravity = u.vec_to_internal(spec.gravity, u.ACCELERATION)
    space.collision_slop = u.to_internal(u.COLLISION_SLOP, u.LENGTH)
    # A pair that separates is forgotten at once: one that touches again within Chipmunk's
    # default 3 steps starts its solve from impulses it never applies (docs/dev/reliability.md).
    space.collision_persistence = 1

    omega = u.to_internal(spec.rotor.angular_velocity, u.ANGULAR_VELOCITY)
    rotor = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    rotor.position = (0.0, 0.0)
    rotor.angular_velocity = omega
    space.add(rotor)

    hammer_bodies: list[pymunk.Body] = []
    hammer_shapes: list[tuple[pymunk.Poly, ...]] = []
    hammer_outlines: list[list[tuple[float, float]]] = []
    hinges: list[pymunk.PivotJoint] = []
    stops: list[pymunk.RotaryLimitJoint] = []
    for h in spec.hammers:
        body, place, joint = _build_hammer(h, rotor, omega)
        if body is not rotor:
            space.add(body)
        shapes = tuple(pymunk.Poly(body, [place(v) for v in piece]) for piece in h.pieces)
        for shape in shapes:
            shape.filter = pymunk.ShapeFilter(group=HAMMER_GROUP)
            space.add(shape)
        if joint is not None:
            space.add(joint)
            hinges.append(joint)
            if h.swing_limit is not None:
                stops.append(_build_stops(h, rotor, body))
                space.add(stops[-1])
        hammer_bodies.append(body)
        hammer_shapes.append(shapes)
        hammer_outlines.append([place(v) for v in h.outline])

    machine = Machine(
        spec=spec,
        space=space,
        rotor=rotor,
        hammer_bodies=hammer_bodies,
        hammer_shapes=hammer_shapes,
        hammer_outlines=hammer_outlines,
        hinges=hinges,
    )
    machine.effects = build_effects(machine)
    if stops:
        machine.effects.append(SwingStops(machine, stops))
    return machine


def _build_hammer(
    h: HammerSpec, rotor: pymunk.Body, omega: float
) -> tuple[pymunk.Body, Callable[[Vec2], Vec2], pymunk.PivotJoint | None]:
    """The hammer's body (the rotor for a welded one), the map of a hammer-frame point (m) to
    the body's frame (internal units), and its hinge joint (None unless hinged)."""
    hinge = u.vec_to_internal(h.hinge_position, u.LENGTH)
    axis_angle = h.angle_on_rotor + h.swing_angle
    if h.mount == "welded":

        def on_rotor(v: Vec2) -> Vec2:
            x, y = _rotate(*u.vec_to_internal(v, u.LENGTH), axis_angle)
            return (hinge[0] + x, hinge[1] + y)

        return rotor, on_rotor, None

    def on_hammer(v: Vec2) -> Vec2:
        return u.vec_to_internal(v, u.LENGTH)

    body = pymunk.Body(
        u.to_internal(h.mass, u.MASS), u.to_internal(h.moment_about_centre, u.MOMENT)
    )
    # order matters: centre of gravity, then angle, then position of the local origin (hinge)
    body.center_of_gravity = u.vec_to_internal(h.centre_of_mass, u.LENGTH)
    body.angle = axis_angle
    body.position = hinge
    if h.mount == "free":
        body.velocity = u.vec_to_internal(h.velocity, u.VELOCITY)
        body.angular_velocity = u.to_internal(h.angular_velocity, u.ANGULAR_VELOCITY)
        return body, on_hammer, None
    # hinged: co-rotate with the rotor (velocity of the centre of gravity = ω × r_cog)
    cog = body.local_to_world(body.center_of_gravity)
    body.velocity = (-omega * cog.y, omega * cog.x)
    body.angular_velocity = omega
    joint = pymunk.PivotJoint(rotor, body, hinge, (0.0, 0.0))
    joint.collide_bodies = False
    return body, on_hammer, joint


def _build_stops(h: HammerSpec, rotor: pymunk.Body, body: pymunk.Body) -> pymunk.RotaryLimitJoint:
    """Stops holding a hinged hammer's α in [−swing_limit, swing_limit]: the hammer's angle
    relative to the rotor is angle_on_rotor + α."""
    assert h.swing_limit is not None
    stops = pymunk.RotaryLimitJoint(
        rotor, body, h.angle_on_rotor - h.swing_limit, h.angle_on_rotor + h.swing_limit
    )
    stops.collide_bodies = False
    return stops
