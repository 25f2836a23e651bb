"""The energy rigid contacts dissipate, and their angular impulse on the rotor-driven bodies,
measured from Chipmunk's arbiters (:class:`ArbiterMeter`).

Per contact the dissipated energy is −J·(v̄_a − v̄_b), J the arbiter's total impulse on the
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

How the contact term is measured: no Python callback. :meth:`ArbiterMeter.before_step` reads
every body's velocity with one ``pymunk.batch`` pass; :meth:`ArbiterMeter.after_step` reads the
space's arbiters (bodies, contact count, total impulse, normal, first contact point on each
shape) and, if any touches, every body's position, angle and velocity, and evaluates the sum
in numpy. Facts of Pymunk 7.3.1's batch API this relies on, each checked against the
per-contact callbacks it replaces (``tests/contact/rigid/test_dissipation.py``):

* The arbiter list is Chipmunk's arbiter cache: besides the contacts solved in this step it
  holds pairs that touched in the last ``collision_persistence`` steps, whose contact count
  reads 0 (and impulse 0). Exactly the arbiters with count > 0 were solved in this step
  (pairs rejected before solving, e.g. two infinite masses, also read 0).
* The order of the two bodies is not the collision handler's (granule first), which the
  callbacks see: read after the step, body ids, normal, impulse and points came out in
  Chipmunk's internal shape order (granule-granule pairs of two materials in both orders;
  checked in ``tests/contact/rigid/test_dissipation.py``). Nothing here depends on the order: the
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

The per-contact terms are summed exactly rounded (``math.fsum``), so that the totals do not
depend on the order in which Chipmunk lists its arbiters, which varies from run to run.

Costs per step: two body reads and one arbiter read (C passes) and numpy over the touching
contacts.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk.batch as pb
from numpy.typing import NDArray

from perga.engine.machine import Machine

_B = pb.BodyFields
_A = pb.ArbiterFields
_BEFORE = _B.BODY_ID | _B.VELOCITY | _B.ANGULAR_VELOCITY  # floats: vx vy w
_AFTER = _B.BODY_ID | _B.POSITION | _B.ANGLE | _B.VELOCITY | _B.ANGULAR_VELOCITY  # x y a vx vy w
# ints: id_a id_b count; floats: J (2), normal (2), point a (2), point b (2)
_ARBITERS = (
    _A.BODY_A_ID | _A.BODY_B_ID | _A.CONTACT_COUNT | _A.TOTAL_IMPULSE | _A.NORMAL
    | _A.POINT_A_1 | _A.POINT_B_1
)  # fmt: skip


class ArbiterMeter:
    """The contact dissipation of a machine's space (internal units, cumulative since it was
    built) and the contacts' angular impulse about the axis on the rotor-driven bodies per
    step. Call :meth:`before_step` immediately before ``space.step`` and :meth:`after_step`
    after it."""

    def __init__(self, machine: Machine) -> None:
        self._space = machine.space
        rotor_driven = {machine.rotor, *(j.b for j in machine.hinges)}
        self._machine_ids = np.array([b.id for b in rotor_driven], dtype=np.uintp)
        self.dissipated = 0.0
        """Energy the contacts dissipated since the meter was built, internal units."""
        self._moment = 0.0  # contact angular impulse on rotor-driven bodies this step
        self._body_buffer = pb.Buffer()
        self._arbiter_buffer = pb.Buffer()
        self._ids0: NDArray[np.uintp] = np.zeros(0, dtype=np.uintp)
        self._table0: NDArray[np.float64] = np.zeros((0, 3))
        self._ids_cache: NDArray[np.uintp] = np.zeros(0, dtype=np.uintp)  # cache of _rows_of
        self._ids_sorted: NDArray[np.uintp] | None = None
        self._order: NDArray[np.intp] = np.zeros(0, dtype=np.intp)
        self._cog_sorted: NDArray[np.float64] = np.zeros((0, 2))

    def before_step(self) -> None:
        """Record every body's velocity at the start of a step."""
        self._ids0, self._table0 = self._bodies_now(_BEFORE, 3)

    def after_step(self) -> float:
        """Add the step's contact dissipation; returns the contacts' angular impulse about the
        axis on the rotor-driven bodies in this step (internal units)."""
        self._moment = 0.0
        self._contacts()
        return self._moment

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

    def touching(self) -> tuple[NDArray[np.uintp], NDArray[np.float64]]:
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
        pair_ids, f = self.touching()
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
        self.dissipated -= 0.5 * math.fsum((impulse * total).ravel())
        if self._machine_ids.size:
            # angular impulse about the axis on a rotor-driven body: +p_a × J on a, −p_b × J on b
            for side, sign in ((0, 1.0), (1, -1.0)):
                machine = np.isin(pair_ids[:, side], self._machine_ids)
                if machine.any():
                    p, j = points[machine, side], impulse[machine]
                    self._moment += sign * math.fsum(p[:, 0] * j[:, 1] - p[:, 1] * j[:, 0])
