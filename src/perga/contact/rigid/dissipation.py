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
every body's velocity before the step (one ``pymunk.batch`` pass over the whole space);
:meth:`ArbiterMeter.after_step` reads the space's arbiters (bodies, contact count, total
impulse, normal, first contact point on each shape) and, if any touches, every body's
position, angle and velocity (a second pass), and evaluates the sum in compiled code. Facts of
Pymunk 7.3.1's batch API this relies on, each checked against the per-contact callbacks it
replaces (``tests/contact/rigid/test_dissipation.py``):

* The arbiter list is Chipmunk's arbiter cache: besides the contacts solved in this step it
  may hold pairs that touched in the last ``collision_persistence`` steps (1 in perga:
  :func:`~perga.machine.machine.build_machine`), whose contact count reads 0 (and impulse 0).
  Exactly the arbiters with count > 0 were solved in this step (pairs rejected before
  solving, e.g. two infinite masses, also read 0).
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

Costs per step: a read of the space and one of the arbiters (C passes); with contacts, another
read of the space, a few numpy operations and one compiled loop over the touching contacts.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pymunk.batch as pb
from numpy.typing import NDArray

from perga.machine.batch import BodyReader
from perga.machine.machine import Machine

_B = pb.BodyFields
_A = pb.ArbiterFields
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
        self._rotor_driven = [machine.rotor, *(j.b for j in machine.hinges)]
        self.dissipated = 0.0
        """Energy the contacts dissipated since the meter was built, internal units."""
        self._start_caches()

    def _start_caches(self) -> None:
        """The per-step values and the caches keyed by body ids (empty: filled at a step)."""
        self._machine_ids = np.array([b.id for b in self._rotor_driven], dtype=np.uintp)
        self._space_reader = BodyReader(self._space, ())
        self._moment = 0.0  # contact angular impulse on rotor-driven bodies this step
        self._arbiter_buffer = pb.Buffer()
        self._ids0: NDArray[np.uintp] = np.zeros(0, dtype=np.uintp)
        self._table0: NDArray[np.float64] = np.zeros((0, 6))
        self._ids_cache: NDArray[np.uintp] = np.zeros(0, dtype=np.uintp)  # cache of _rows_of
        self._ids_sorted: NDArray[np.uintp] | None = None
        self._order: NDArray[np.intp] = np.zeros(0, dtype=np.intp)
        self._cog_sorted: NDArray[np.float64] = np.zeros((0, 2))

    def __getstate__(self) -> dict[str, object]:
        """The meter's state (a checkpoint) without the arbiter buffer (C memory) and the
        caches keyed by body ids, which a pickled body does not keep."""
        return {k: self.__dict__[k] for k in ("_space", "_rotor_driven", "dissipated")}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._arbiter_buffer = pb.Buffer()
        self._machine_ids = np.zeros(0, dtype=np.uintp)  # the bodies may not be rebuilt yet

    def before_step(self) -> None:
        """Keep every body's velocity at the start of a step: call immediately before
        ``space.step``."""
        if self._machine_ids.size != len(self._rotor_driven):  # first step after unpickling
            self._start_caches()
        self._ids0, self._table0 = self._space_reader.read_internal_space()

    def after_step(self) -> float:
        """Add the step's contact dissipation: call immediately after ``space.step``, before
        anything changes a body; returns the contacts' angular impulse about the axis on the
        rotor-driven bodies in this step (internal units)."""
        self._moment = 0.0
        self._contacts()
        return self._moment

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
        ids, after = self._space_reader.read_internal_space()
        where = self._rows_of(ids, pair_ids.ravel())  # rows in the sorted order
        rows = self._order[where].reshape(-1, 2)
        if np.array_equal(self._ids0, ids):
            rows0 = rows
        else:  # the body arrays changed during the step (not expected): look the ids up again
            order0 = np.argsort(self._ids0, kind="stable")
            rows0 = order0[np.searchsorted(self._ids0[order0], pair_ids)]
        cog_local = self._cog_sorted[where].reshape(-1, 2, 2)
        loss, moment = _arbiter_terms(
            f, rows, rows0, after, self._table0, cog_local, pair_ids, self._machine_ids
        )
        self.dissipated -= 0.5 * math.fsum(loss.ravel())
        if self._machine_ids.size:
            self._moment += math.fsum(moment[:, 0])
            self._moment += -math.fsum(moment[:, 1])


@numba.njit(cache=True)
def _arbiter_terms(
    f: NDArray[np.float64],
    rows: NDArray[np.intp],
    rows0: NDArray[np.intp],
    after: NDArray[np.float64],
    before: NDArray[np.float64],
    cog: NDArray[np.float64],
    pair_ids: NDArray[np.uintp],
    machine_ids: NDArray[np.uintp],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per touching arbiter (floats ``f``: J, normal, the two contact points), the terms of its
    dissipation, J_x·ū_x and J_y·ū_y with ū the sum of the relative velocities of the contact
    points before and after the step (module doc), and of the angular impulse about the axis
    on each of its bodies that is rotor-driven (its id, ``pair_ids``, among ``machine_ids``),
    p × J (0 where not). ``rows`` / ``rows0``: the two bodies' rows in the space's tables
    after and before the step (x y angle vx vy w); ``cog``: their centres of gravity in their
    own frames."""
    m = f.shape[0]
    loss = np.empty((m, 2))
    moment = np.zeros((m, 2))
    for c in range(m):
        jx, jy, nx, ny = f[c, 0], f[c, 1], f[c, 2], f[c, 3]
        swapped = (f[c, 6] - f[c, 4]) * nx + (f[c, 7] - f[c, 5]) * ny > 0
        u = np.empty((2, 4))  # per side: ux, uy before the step, ux, uy after it
        for side in range(2):
            own = 6 if swapped == (side == 0) else 4  # each body's own contact point
            px, py = f[c, own], f[c, own + 1]
            k = rows[c, side]
            angle = after[k, 2]
            cos, sin = math.cos(angle), math.sin(angle)
            cx = after[k, 0] + cos * cog[c, side, 0] - sin * cog[c, side, 1]
            cy = after[k, 1] + sin * cog[c, side, 0] + cog[c, side, 1] * cos
            rx, ry = px - cx, py - cy
            k0 = rows0[c, side]
            u[side, 0] = before[k0, 3] - before[k0, 5] * ry
            u[side, 1] = before[k0, 4] + before[k0, 5] * rx
            u[side, 2] = after[k, 3] - after[k, 5] * ry
            u[side, 3] = after[k, 4] + after[k, 5] * rx
            for driven in machine_ids:
                if pair_ids[c, side] == driven:
                    moment[c, side] = px * jy - py * jx
        loss[c, 0] = jx * ((u[0, 0] - u[1, 0]) + (u[0, 2] - u[1, 2]))
        loss[c, 1] = jy * ((u[0, 1] - u[1, 1]) + (u[0, 3] - u[1, 3]))
    return loss, moment
