"""Energy ledger: every term measured on its own, so that their balance is a real check.

Per step Chipmunk changes each body's velocity by impulses (contacts, joints, motors) and kicks
(gravity, the effects' per-step kicks). For one body the exact change of kinetic energy
over the step is Σ J·v̄ over those impulses, v̄ the mean of the velocities at the application
point before and after the step. The ledger uses that identity term by term:

* ``contact_dissipation``: per contact, −J·(v̄_a − v̄_b), J the arbiter's total impulse on the
  first body, v_a, v_b the two bodies' velocities at their own contact points, taken at the
  start of the step (before gravity, kicks and impulses: what ``pre_solve`` sees) and at its
  end (what ``post_solve`` sees). This is exact for one contact (it reproduces ½μ(1 − e²)w²
  of a free impact to rounding) and covers restitution losses, dynamic and static friction
  alike. Chipmunk's ``arbiter.total_ke`` is not used: it assumes one impact and ignores
  dynamic friction. Limits:
  where several impulses act on a body in one step each contact is still charged with the
  body's whole-step mean velocity, which is the exact split of ΔKE but attributes the other
  impulses' cross terms to the contacts, and when gravity or a kick acts in the same step the
  velocity before includes neither (the kick's energy is counted by the kick itself at its own
  velocities), so the split is exact to first order in dt; Chipmunk's position correction
  (``v_bias``) moves bodies without changing velocities and is not an energy term.
* ``drive_work``: the work the rotor does on the rest, impulse × the rotor's velocity at the
  application point. Chipmunk exposes only |impulse| for a pivot joint or motor, so the rotor's
  angular impulse about its axis is measured through the angular momentum balance of the
  rotor-driven bodies (hinged hammers, plus the rotor itself when it is driven): ΔL about the
  axis, minus the contact impulses on those bodies and on welded hammers (from the arbiters)
  and minus gravity's moment; times the rotor's angular velocity (its mean over the step when
  driven). This is the moment equation, not the energy equation, so the closure remains an
  independent check. The co-rotating floor's work comes from its own kicks.
  Hammers hitting their swing stops add what the stops removed (``effects.SwingStops``).
* ``friction``, ``drag``: what the effects removed (:mod:`perga.engine.effects`).
* ``gravity_work``: the potential energy released by in-plane gravity, Σ m g·Δr_cg.
* ``closure`` = (drive_work + gravity_work − ΔKE − contact_dissipation − friction − drag) /
  max(|drive_work|, |ΔKE|, |gravity_work|, ½Σ_i|ΔKE_i|, 1e-30 J): the pivot joints' error
  correction, the first-order split of the kicks and rounding, nothing else. The term
  ½Σ_i|ΔKE_i| (kinetic energy moved between bodies) keeps the closure meaningful where nothing
  is driven or lost, e.g. an elastic free impact (ΔKE = 0).

How the contact term is measured: no Python callback. :meth:`EnergyMeter.before_step` reads
every body's velocity with one ``pymunk.batch`` pass; :meth:`EnergyMeter.after_step` reads the
space's arbiters (bodies, contact count, total impulse, normal, first contact point on each
shape) and, if any touches, every body's position, angle and velocity, and evaluates the sum
in numpy. Facts of Pymunk 7.3.1's batch API this relies on, each checked against the
per-contact callbacks it replaces (``tests/engine/test_energy.py``):

* The arbiter list is Chipmunk's arbiter cache: besides the contacts solved in this step it
  holds pairs that touched in the last ``collision_persistence`` steps, whose contact count
  reads 0 (and impulse 0). Exactly the arbiters with count > 0 were solved in this step
  (pairs rejected before solving, e.g. two infinite masses, also read 0).
* The order of the two bodies is not the collision handler's (granule first), which the
  callbacks see: read after the step, body ids, normal, impulse and points came out in
  Chipmunk's internal shape order (granule-granule pairs of two materials in both orders;
  checked in ``tests/engine/test_energy.py``). Nothing here depends on the order: the
  dissipation is symmetric in a and b and the contact moment is taken on whichever body is
  rotor-driven. Chipmunk's own getters differ in whether they undo an arbiter's swap (ids,
  normal, impulse do; points do not), so the points are matched to the bodies by the sign of
  (P_b − P_a)·normal, which is < 0 (penetration) for every touching contact in consistent
  order.
* Positions do not change during the solve, so the contact points read after the step are
  those of ``pre_solve``, and velocities read before ``space.step`` are those ``pre_solve``
  sees (positions are integrated first, velocities only after the collision callbacks).
  A body's velocity at a world point is v + ω × (p − c), c its centre of gravity in world
  coordinates (position + rotated ``center_of_gravity``).
* Only the first contact point is used, as before: granules are circles (one point per
  arbiter); a two-point arbiter would be charged at its first point.

Costs per step: two body reads and one arbiter read (C passes), numpy over the touching
contacts, a loop over the few rotor-driven bodies; a loop over all bodies only when
:meth:`EnergyMeter.ledger` is called.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymunk
import pymunk.batch as pb
from numpy.typing import NDArray

from perga.engine import units as u
from perga.engine.machine import Scene

_B = pb.BodyFields
_A = pb.ArbiterFields
_BEFORE = _B.BODY_ID | _B.VELOCITY | _B.ANGULAR_VELOCITY  # floats: vx vy w
_AFTER = _B.BODY_ID | _B.POSITION | _B.ANGLE | _B.VELOCITY | _B.ANGULAR_VELOCITY  # x y a vx vy w
# ints: id_a id_b count; floats: J (2), normal (2), point a (2), point b (2)
_ARBITERS = (
    _A.BODY_A_ID | _A.BODY_B_ID | _A.CONTACT_COUNT | _A.TOTAL_IMPULSE | _A.NORMAL
    | _A.POINT_A_1 | _A.POINT_B_1
)  # fmt: skip

TINY = 1e-30
"""J: the closure's denominator floor (a scene where nothing moves has closure 0)."""


@dataclass(frozen=True)
class EnergyLedger:
    """Cumulative energy terms since t = 0, J (SI); ``closure`` is dimensionless."""

    kinetic: float
    """Current kinetic energy of all dynamic bodies (translation and rotation)."""
    kinetic_initial: float
    """Kinetic energy at t = 0."""
    drive_work: float
    """Work done by the rotor (kinematic or driven) on the other bodies."""
    gravity_work: float
    """Work done by in-plane gravity (potential energy released)."""
    contact_dissipation: float
    """Energy lost in granule-hammer, granule-granule and granule-wall contacts."""
    friction: float
    """Energy removed by floor and hinge friction."""
    drag: float
    """Energy removed by air drag."""
    closure: float
    """(drive + gravity − ΔKE − Δelastic − contact − friction − drag) / energy scale (module
    doc)."""
    elastic: float = 0.0
    """Energy stored in soft contacts now (0 with rigid contacts)."""
    elastic_initial: float = 0.0
    """Energy stored in soft contacts at t = 0."""


@dataclass(frozen=True)
class LedgerTerms:
    """The measured terms of a ledger before closing it (J): see :class:`EnergyLedger`;
    ``moved`` is ½Σ_i|ΔKE_i|, the kinetic energy moved between bodies."""

    kinetic: float
    kinetic_initial: float
    moved: float
    drive_work: float
    gravity_work: float
    contact_dissipation: float
    friction: float
    drag: float
    elastic: float = 0.0
    elastic_initial: float = 0.0

    def close(self) -> EnergyLedger:
        """The ledger with its closure (module doc)."""
        change = self.kinetic - self.kinetic_initial + self.elastic - self.elastic_initial
        residual = (
            self.drive_work
            + self.gravity_work
            - change
            - self.contact_dissipation
            - self.friction
            - self.drag
        )
        scale = max(abs(self.drive_work), abs(change), abs(self.gravity_work), self.moved, TINY)
        return EnergyLedger(
            kinetic=self.kinetic,
            kinetic_initial=self.kinetic_initial,
            drive_work=self.drive_work,
            gravity_work=self.gravity_work,
            contact_dissipation=self.contact_dissipation,
            friction=self.friction,
            drag=self.drag,
            closure=residual / scale,
            elastic=self.elastic,
            elastic_initial=self.elastic_initial,
        )


def _kinetic(body: pymunk.Body) -> float:
    """½m|v|² + ½Iω² (internal units); no rotational term for an infinite moment."""
    spin = 0.0 if body.moment == float("inf") else body.moment * body.angular_velocity**2
    return 0.5 * (body.mass * body.velocity.dot(body.velocity) + spin)


def _centre(body: pymunk.Body) -> pymunk.Vec2d:
    return body.local_to_world(body.center_of_gravity)


class EnergyMeter:
    """Measures the ledger's terms of one scene from the moment it is built (see module doc).

    Call :meth:`before_step` and :meth:`after_step` around every ``space.step``.
    """

    def __init__(self, scene: Scene) -> None:
        self._scene = scene
        self._space = scene.space
        self._rotor = scene.rotor
        driven = scene.rotor.body_type == pymunk.Body.DYNAMIC
        self._bodies = [b for b in scene.space.bodies if b.body_type == pymunk.Body.DYNAMIC]
        hinged = [j.b for j in scene.joints]
        self._machine = ([scene.rotor] if driven else []) + hinged
        self._machine_set = {scene.rotor, *hinged}
        self._needs_balance = bool(self._machine or scene.rotor.shapes)
        self._kinetics0 = [_kinetic(b) for b in self._bodies]
        self._centres0 = [_centre(b) for b in self._bodies]
        self._contact = 0.0
        self._drive = 0.0
        self._moment = 0.0  # contact angular impulse on rotor-driven bodies this step
        self._before: list[tuple[pymunk.Vec2d, float]] = []
        self._machine_ids = np.array([b.id for b in self._machine_set], dtype=np.uintp)
        self._body_buffer = pb.Buffer()
        self._arbiter_buffer = pb.Buffer()
        self._ids0: NDArray[np.uintp] = np.zeros(0, dtype=np.uintp)
        self._table0: NDArray[np.float64] = np.zeros((0, 3))
        self._ids_cache: NDArray[np.uintp] = np.zeros(0, dtype=np.uintp)  # cache of _rows_of
        self._ids_sorted: NDArray[np.uintp] | None = None
        self._order: NDArray[np.intp] = np.zeros(0, dtype=np.intp)
        self._cog_sorted: NDArray[np.float64] = np.zeros((0, 2))

    # --- contacts (batch reads, see the module doc) ----------------------------------------

    def _bodies_now(
        self, fields: pb.BodyFields, width: int
    ) -> tuple[NDArray[np.uintp], NDArray[np.float64]]:
        """One batch read of every body: ids (copy) and an (n, width) float table (copy)."""
        buffer = self._body_buffer
        buffer.clear()
        pb.get_space_bodies(self._space, fields, buffer)
        ids = np.frombuffer(buffer.int_buf(), dtype=np.uintp).copy()
        floats = np.frombuffer(buffer.float_buf(), dtype=np.float64)
        if floats.size != ids.size * width:
            raise RuntimeError(
                f"pymunk.batch returned {floats.size} floats for {ids.size} bodies, expected "
                f"{width} per body: the experimental batch layout has changed"
            )
        return ids, floats.reshape(ids.size, width).copy()

    def _touching(self) -> tuple[NDArray[np.uintp], NDArray[np.float64]]:
        """Body ids (m, 2), handler order, and floats (m, 8) of the arbiters solved this step."""
        buffer = self._arbiter_buffer
        buffer.clear()
        pb.get_space_arbiters(self._space, _ARBITERS, buffer)
        ints = np.frombuffer(buffer.int_buf(), dtype=np.uintp)
        floats = np.frombuffer(buffer.float_buf(), dtype=np.float64)
        n = ints.size // 3
        if ints.size != 3 * n or floats.size != 8 * n:
            raise RuntimeError(
                f"pymunk.batch returned {ints.size} ints and {floats.size} floats for the "
                "arbiters, expected 3 and 8 per arbiter: the experimental batch layout has changed"
            )
        ints = ints.reshape(n, 3)
        touching = ints[:, 2] > 0
        return ints[touching, :2], floats.reshape(n, 8)[touching]

    def _rows_of(self, ids: NDArray[np.uintp], wanted: NDArray[np.uintp]) -> NDArray[np.intp]:
        """Row in ``ids`` (one batch read's id column) of each id in ``wanted``."""
        if self._ids_sorted is None or not np.array_equal(self._ids_cache, ids):
            order = np.argsort(ids, kind="stable")
            self._ids_cache = ids
            self._ids_sorted = ids[order]
            self._order = order
            cogs = {b.id: tuple(b.center_of_gravity) for b in self._space.bodies}
            cogs[self._space.static_body.id] = (0.0, 0.0)
            self._cog_sorted = np.array(
                [cogs.get(int(i), (0.0, 0.0)) for i in self._ids_sorted], dtype=float
            ).reshape(-1, 2)
        where = np.searchsorted(self._ids_sorted, wanted)
        where[where >= self._ids_sorted.size] = 0
        if not np.array_equal(self._ids_sorted[where], wanted):
            raise LookupError("an arbiter's body is not among the space's bodies")
        return where

    def _contacts(self) -> None:
        """Add this step's contact dissipation and contact moment on rotor-driven bodies."""
        pair_ids, f = self._touching()
        if pair_ids.shape[0] == 0:
            return
        ids, after = self._bodies_now(_AFTER, 6)
        where = self._rows_of(ids, pair_ids.ravel())  # rows in the sorted order
        rows = self._order[where].reshape(-1, 2)
        if np.array_equal(self._ids0, ids):
            before = self._table0[rows]
        else:  # the body arrays changed during the step (not expected): look the ids up again
            order0 = np.argsort(self._ids0, kind="stable")
            before = self._table0[order0[np.searchsorted(self._ids0[order0], pair_ids)]]
        cog_local = self._cog_sorted[where].reshape(-1, 2, 2)
        state = after[rows]  # (m, 2, 6): x y angle vx vy w
        cos, sin = np.cos(state[..., 2]), np.sin(state[..., 2])
        centre_x = state[..., 0] + cos * cog_local[..., 0] - sin * cog_local[..., 1]
        centre_y = state[..., 1] + sin * cog_local[..., 0] + cog_local[..., 1] * cos
        impulse, normal, p1, p2 = f[:, 0:2], f[:, 2:4], f[:, 4:6], f[:, 6:8]
        swapped = ((p2 - p1) * normal).sum(axis=1) > 0
        points = np.stack(
            [np.where(swapped[:, None], p2, p1), np.where(swapped[:, None], p1, p2)], axis=1
        )  # (m, 2, 2): each body's own contact point
        rx, ry = points[..., 0] - centre_x, points[..., 1] - centre_y

        def relative(v: NDArray[np.float64]) -> NDArray[np.float64]:
            # v: (m, 2, 3) vx vy w; velocity of a at its point minus b's at its point
            ux = v[..., 0] - v[..., 2] * ry
            uy = v[..., 1] + v[..., 2] * rx
            return np.stack([ux[:, 0] - ux[:, 1], uy[:, 0] - uy[:, 1]], axis=1)

        total = relative(before) + relative(state[..., 3:6])
        self._contact -= 0.5 * float(np.sum(impulse * total))
        if self._machine_ids.size:
            # angular impulse about the axis on a rotor-driven body: +p_a × J on a, −p_b × J on b
            for side, sign in ((0, 1.0), (1, -1.0)):
                machine = np.isin(pair_ids[:, side], self._machine_ids)
                if machine.any():
                    p, j = points[machine, side], impulse[machine]
                    self._moment += sign * float(np.sum(p[:, 0] * j[:, 1] - p[:, 1] * j[:, 0]))

    # --- the rotor's angular momentum balance ------------------------------------------------

    def before_step(self) -> None:
        """Record the bodies' velocities at the start of a step: call it immediately before
        ``space.step`` (after anything else that changes velocities between steps)."""
        self._ids0, self._table0 = self._bodies_now(_BEFORE, 3)
        if not self._needs_balance:
            return
        self._before = [(b.velocity, b.angular_velocity) for b in self._machine]
        self._omega0 = self._rotor.angular_velocity

    def after_step(self, dt: float) -> None:
        """Add the step's contact dissipation and drive work; ``dt`` in internal time units."""
        self._contacts()
        if not self._needs_balance:
            return
        gravity = self._space.gravity
        moment = -self._moment
        for body, (v0, w0) in zip(self._machine, self._before, strict=True):
            r = _centre(body)
            moment += body.mass * r.cross(body.velocity - v0 - gravity * dt)
            moment += body.moment * (body.angular_velocity - w0)
        self._drive += 0.5 * (self._omega0 + self._rotor.angular_velocity) * moment
        self._moment = 0.0

    # --- the ledger ------------------------------------------------------------------------

    def add_moment(self, angular_impulse: float) -> None:
        """Add an external angular impulse about the axis on the rotor-driven bodies in this
        step (internal units), e.g. soft granules' loads on hinged hammers: call it between
        :meth:`before_step` and :meth:`after_step`."""
        self._moment += angular_impulse

    def terms(self) -> LedgerTerms:
        """The cumulative terms of the Pymunk bodies and the effects now, in J."""
        gravity = self._space.gravity
        kinetics = [_kinetic(b) for b in self._bodies]
        terms = {"friction": 0.0, "drag": 0.0, "drive": 0.0, "contact": 0.0}
        supplied = 0.0
        for effect in self._scene.effects:
            terms[effect.term] += effect.removed
            supplied += effect.supplied
        return LedgerTerms(
            kinetic=sum(kinetics) * u.ENERGY,
            kinetic_initial=sum(self._kinetics0) * u.ENERGY,
            moved=0.5
            * sum(abs(k - k0) for k, k0 in zip(kinetics, self._kinetics0, strict=True))
            * u.ENERGY,
            drive_work=self._drive * u.ENERGY + supplied,
            gravity_work=sum(
                b.mass * gravity.dot(_centre(b) - r0)
                for b, r0 in zip(self._bodies, self._centres0, strict=True)
            )
            * u.ENERGY,
            contact_dissipation=self._contact * u.ENERGY + terms["contact"],
            friction=terms["friction"],
            drag=terms["drag"],
        )

    def ledger(self) -> EnergyLedger:
        """The cumulative terms now, in J, and their closure."""
        return self.terms().close()
