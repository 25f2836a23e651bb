"""Granule-hammer impacts of rigid (impulse) contacts, as :class:`~perga.model.records.Impact`
rows.

An impact is the first step of a granule-hammer contact. Chipmunk moves the bodies, then finds
contacts: a new contact's ``begin`` (or, where ``pre_solve`` rewrites contacts, its first
processed ``pre_solve``, after the rewrite) stores the relative contact velocity, the granule's
kinetic energy and velocity and the hammer's state, read after the step's position update and
before its impulses; its first ``post_solve`` completes the row with the velocities after the
impulses, the impulse and the energy dissipated in the contact, −J·v̄_rel with v̄_rel the mean
of the relative contact velocity before and after (exact for one impulse).

A contact goes on while any piece of the hammer touches the granule; when the last separates it
is written as a :class:`~perga.model.records.Contact`: its first state is the granule's after
its first step's impulses (the impact's "after"), its last the granule's after its last step's,
its other contacts the most the granule had in any of its steps, its touches the granule's
contacts with other granules and the wall begun before its first step's end. A contact still
open when the run ends is not written.
"""

from __future__ import annotations

import math
from collections.abc import Container
from dataclasses import dataclass, field, replace

import pymunk

from perga.contact.rigid.bodies import RigidBodies
from perga.machine import units as u
from perga.model.records import Contact, HammerState, Impact


def _contact(arbiter: pymunk.Arbiter) -> tuple[pymunk.Vec2d, pymunk.Vec2d, pymunk.Vec2d]:
    """Relative velocity granule − hammer at the contact (internal units), the contact point
    (midway between the two surfaces) and the hammer's outward normal. Shapes are ordered
    (granule, hammer). Each body's velocity is taken at its own contact point, where Chipmunk
    applies its impulse (the granule's on its rim): the slip the impulse acts on, so that
    −J·v̄_rel is exactly what the impulse dissipates, a spinning granule's included."""
    granule_shape, hammer_shape = arbiter.shapes
    outward = -arbiter.normal  # arbiter.normal points from the granule to the hammer
    point = arbiter.contact_point_set.points[0]
    v_g = granule_shape.body.velocity_at_world_point(point.point_a)
    v_h = hammer_shape.body.velocity_at_world_point(point.point_b)
    return v_g - v_h, (point.point_a + point.point_b) * 0.5, outward


def _granule_energy(body: pymunk.Body) -> float:
    """Kinetic energy of a granule body, internal units (a sliding point has moment inf)."""
    spin = 0.0 if math.isinf(body.moment) else 0.5 * body.moment * body.angular_velocity**2
    return 0.5 * body.mass * body.velocity.length_squared + spin


def _spin(body: pymunk.Body) -> float:
    """A granule body's angular velocity, rad/s."""
    return u.to_si(body.angular_velocity, u.ANGULAR_VELOCITY)


def _other_contacts(arbiter: pymunk.Arbiter, *, hammer_side: bool = True) -> int:
    """Touching contacts in this step on the granule, and (``hammer_side``) on the hammer unless
    its body moves as prescribed (kinematic: no contact changes its motion), but those of this
    granule with this hammer body (its other pieces belong to this impact)."""
    granule, hammer = (shape.body for shape in arbiter.shapes)
    touching: list[pymunk.Arbiter] = []
    granule.each_arbiter(touching.append)
    if hammer_side and hammer.body_type == pymunk.Body.DYNAMIC:
        hammer.each_arbiter(touching.append)
    pair = {granule, hammer}
    return sum(
        bool(a.contact_point_set.points) and {s.body for s in a.shapes} != pair for a in touching
    )


_Pending = tuple[pymunk.Vec2d, float, pymunk.Vec2d, float, HammerState]


@dataclass
class _Granule:
    """A granule body's position (m), velocity (m/s) and spin (rad/s), and its hammer body's
    angle (rad) and angular velocity (rad/s), at one time (s)."""

    time: float
    position: tuple[float, float]
    velocity: tuple[float, float]
    spin: float
    hammer_angle: float
    hammer_omega: float

    @classmethod
    def read(cls, time: float, arbiter: pymunk.Arbiter) -> _Granule:
        granule, hammer = (shape.body for shape in arbiter.shapes)
        return cls(
            time,
            u.vec_to_si(tuple(granule.position), u.LENGTH),
            u.vec_to_si(tuple(granule.velocity), u.VELOCITY),
            _spin(granule),
            hammer.angle,
            u.to_si(hammer.angular_velocity, u.ANGULAR_VELOCITY),
        )


@dataclass
class _Open:
    """A contact going on: its first and last states, its steps, the most other contacts the
    granule had in one of them, its touching shape pairs."""

    first: _Granule
    normal: tuple[float, float]
    held: bool
    touches: int
    last: _Granule
    steps: int = 1
    others: int = 0
    shapes: set[tuple[pymunk.Shape, pymunk.Shape]] = field(default_factory=set)

    def contact(self, granule: int, hammer: int) -> Contact:
        a, b = self.first, self.last
        return Contact(
            granule=granule,
            hammer=hammer,
            start=a.time,
            end=b.time,
            steps=self.steps,
            normal=self.normal,
            position_start=a.position,
            velocity_start=a.velocity,
            spin_start=a.spin,
            position_end=b.position,
            velocity_end=b.velocity,
            spin_end=b.spin,
            hammer_turn=b.hammer_angle - a.hammer_angle,
            hammer_angular_velocity_start=a.hammer_omega,
            hammer_angular_velocity_end=b.hammer_omega,
            other_contacts=self.others,
            held=self.held,
            touches=self.touches,
        )


class RigidImpactLog:
    """Records the first step of every granule-hammer contact as an :class:`Impact`.

    A granule touching two convex pieces of one hammer in the same step (a notch) makes two
    Chipmunk contacts but one impact: their impulses along the first contact's normal and their
    dissipation are summed into the first one's row. With ``rewritten`` (contacts that
    ``pre_solve`` replaces or drops: hammers of several pieces, :mod:`~perga.contact.rigid.
    outline`; sliding points, :mod:`~perga.contact.rigid.sliding_point`) an impact starts at a
    contact's first processed ``pre_solve``, after those listeners, so that its velocities
    before and after are taken at the same points. ``held``: the ids of the granules held in
    their cells (the contact model's, kept up to date by it).
    """

    def __init__(
        self,
        bodies: RigidBodies,
        held: Container[int],
        *,
        rewritten: bool = False,
    ) -> None:
        self.impacts: list[Impact] = []
        self._contacts: list[Contact] = []
        self._ended: list[Contact] = []  # since the last read, in Chipmunk's order
        self._held = held
        self.time = 0.0
        self._machine = bodies.machine
        self._owner = bodies.shape_owner
        # (granule shape, hammer shape) -> relative contact velocity, granule KE and velocity,
        # hammer state (None once recorded); (granule, hammer) -> its impact's row in this step
        self._pending: dict[tuple[pymunk.Shape, pymunk.Shape], _Pending | None] = {}
        self._rows: dict[tuple[int, int], int] = {}
        self._rows_time = -1.0
        self._open: dict[tuple[int, int], _Open] = {}  # (granule, hammer) -> its contact
        self._touches: dict[int, int] = {}  # granule -> contacts begun with granules, the wall
        start = "pre_solve" if rewritten else "begin"
        bodies.listen(start, self._start, ("granule", "hammer"))
        bodies.listen("post_solve", self._post_solve, ("granule", "hammer"))
        bodies.listen("separate", self._separate, ("granule", "hammer"))
        bodies.listen("begin", self._touch, ("granule", "granule"))
        bodies.listen("begin", self._touch, ("granule", "wall"))

    def _key(self, arbiter: pymunk.Arbiter) -> tuple[int, int]:
        granule_shape, hammer_shape = arbiter.shapes
        return self._owner[granule_shape][1], self._owner[hammer_shape][1]

    def _start(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        if not arbiter.process_collision or tuple(arbiter.shapes) in self._pending:
            return
        relative, _, _ = _contact(arbiter)
        body = arbiter.shapes[0].body
        state = self._machine.hammer_state(self._key(arbiter)[1])
        pending = (relative, _granule_energy(body), body.velocity, _spin(body), state)
        self._pending[tuple(arbiter.shapes)] = pending  # type: ignore[index]

    def _post_solve(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        shapes = tuple(arbiter.shapes)
        self._go_on(arbiter, shapes)
        pending = self._pending.get(shapes)  # type: ignore[call-overload]
        if pending is None:
            return
        self._pending[shapes] = None  # type: ignore[index]
        key = self._key(arbiter)
        before, granule_energy, granule_velocity, spin, hammer = pending
        after, point, n = _contact(arbiter)
        t = n.perpendicular()
        # measured: total_impulse is the impulse on the first shape's body (the granule)
        impulse = arbiter.total_impulse
        joule = u.to_si(1.0, u.ENERGY)
        dissipated = -impulse.dot((before + after) * 0.5) * joule
        if self._rows_time != self.time:
            self._rows, self._rows_time = {}, self.time
        row = self._rows.get(key)
        if row is not None:  # a second piece of the same hammer in the same step
            first = self.impacts[row]
            n_first = pymunk.Vec2d(*first.normal)
            self.impacts[row] = replace(
                first,
                normal_impulse=first.normal_impulse + u.to_si(impulse.dot(n_first), u.IMPULSE),
                dissipated=first.dissipated + dissipated,
            )
            return
        self._rows[key] = len(self.impacts)
        self.impacts.append(
            Impact(
                time=self.time,
                granule=key[0],
                hammer=key[1],
                normal_velocity_before=u.to_si(before.dot(n), u.VELOCITY),
                normal_velocity_after=u.to_si(after.dot(n), u.VELOCITY),
                tangential_velocity_before=u.to_si(before.dot(t), u.VELOCITY),
                tangential_velocity_after=u.to_si(after.dot(t), u.VELOCITY),
                normal_impulse=u.to_si(impulse.dot(n), u.IMPULSE),
                point=u.vec_to_si(tuple(point), u.LENGTH),
                normal=(n.x, n.y),
                granule_energy_gain=(_granule_energy(arbiter.shapes[0].body) - granule_energy)
                * joule,
                dissipated=dissipated,
                hammer_energy_before=hammer.energy,
                granule_velocity_before=u.vec_to_si(tuple(granule_velocity), u.VELOCITY),
                hammer_swing_angle_before=hammer.swing_angle,
                hammer_angular_velocity_before=hammer.angular_velocity,
                hammer_centre_before=hammer.centre,
                granule_spin_before=spin,
                granule_spin_after=_spin(arbiter.shapes[0].body),
                granule_velocity_after=u.vec_to_si(
                    tuple(arbiter.shapes[0].body.velocity), u.VELOCITY
                ),
                held=key[0] in self._held,
                other_contacts=_other_contacts(arbiter),
            )
        )

    def _go_on(self, arbiter: pymunk.Arbiter, shapes: tuple) -> None:
        """Open the pair's contact at its first solved step or take this step's state."""
        key = self._key(arbiter)
        others = _other_contacts(arbiter, hammer_side=False)
        contact = self._open.get(key)
        if contact is None:
            now = _Granule.read(self.time, arbiter)
            held, touches = key[0] in self._held, self._touches.get(key[0], 0)
            contact = _Open(now, tuple(-arbiter.normal), held, touches, now)
            self._open[key] = contact
        elif contact.last.time != self.time:
            contact.last = _Granule.read(self.time, arbiter)
            contact.steps += 1
        contact.others = max(contact.others, others)
        contact.shapes.add(shapes)

    def _touch(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        """Count a contact begun with another granule or the wall on each granule of it."""
        for shape in arbiter.shapes:
            kind, id_ = self._owner.get(shape, ("wall", -1))
            if kind == "granule":
                self._touches[id_] = self._touches.get(id_, 0) + 1

    def _separate(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        shapes = tuple(arbiter.shapes)
        self._pending.pop(shapes, None)  # type: ignore[arg-type]
        key = self._key(arbiter)
        contact = self._open.get(key)
        if contact is None:
            return
        contact.shapes.discard(shapes)
        if not contact.shapes:
            del self._open[key]
            self._ended.append(contact.contact(*key))

    @property
    def contacts(self) -> list[Contact]:
        """The contacts ended so far, those ended since the last read in the order of their end,
        granule and hammer (Chipmunk separates pairs in the order of its hash table, which a
        restored space does not keep)."""
        if self._ended:
            self._ended.sort(key=lambda c: (c.end, c.granule, c.hammer))
            self._contacts += self._ended
            self._ended = []
        return self._contacts
