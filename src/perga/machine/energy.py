"""The energy ledger: every term measured on its own, so that their balance is a real check.

Per step each body's velocity changes by impulses (contacts, joints, motors) and kicks (gravity,
the effects' per-step kicks). For one body the exact change of kinetic energy over the step is
Σ J·v̄ over those impulses, v̄ the mean of the velocities at the application point before and
after the step. The ledger uses that identity term by term. Its parts:

* :class:`EnergyMeter` (here): the machine's dynamic bodies (a driven rotor, hinged or free
  hammers): their kinetic energy and gravity's work on them, the drive's work and what the
  effects removed.
* the contact model's own terms (:meth:`perga.contact.protocol.ContactModel.energy_terms`):
  the granules' kinetic (and, soft, elastic) energy, gravity's work on them, what granules fed
  in brought and granules taken out took, and the energy its contacts dissipated.

The terms:

* ``drive_work``: the work the rotor does on the rest, impulse × the rotor's velocity at the
  application point. Chipmunk exposes only |impulse| for a pivot joint or motor, so the rotor's
  angular impulse about its axis is measured through the angular momentum balance of the
  rotor-driven bodies (hinged hammers, plus the rotor itself when it is driven): ΔL about the
  axis, minus the contact model's angular impulse on those bodies and on welded hammers
  (``contact_moment`` of :meth:`EnergyMeter.after_step`) and minus gravity's moment; times the
  rotor's angular velocity (its mean over the step when driven). This is the moment equation,
  not the energy equation, so the closure remains an independent check. The co-rotating floor's
  work comes from its own kicks. Hammers hitting their swing stops add what the stops removed
  (:class:`~perga.machine.effects.SwingStops`).
* ``contact_dissipation``: the contact model's, plus the swing stops' losses.
* ``friction``, ``drag``: what the effects removed (:mod:`perga.machine.effects`).
* ``gravity_work``: the potential energy released by in-plane gravity, Σ m g·Δr_cg.
* ``joint_correction``: the work the pins' position correction did, Σ J·(v̄_hammer − v̄_rotor)
  at each hinge and −J·v̄_rotor at a driven rotor's axis per step (:func:`_pivot_work`; J the
  pin's impulse, read raw through :class:`~perga.machine.chipmunk_state.JointImpulses`): an
  ideal pin does none; Chipmunk's pulls the drifting anchors together and does, first order
  in dt. Unbooked, it was the whole residual before a run's first impact
  (docs/dev/reliability.md).
* ``residual`` = drive_work + gravity_work + joint_correction + inflow − outflow − ΔKE −
  Δelastic − contact_dissipation − friction − drag, J: what the steps lose or make besides
  that (the first-order split of the kicks, such as gravity's on a rigid contact; the soft
  kernel's step; each falls with the step, docs/dev/reliability.md)
  and rounding (the swing stops' and hinge friction's work is booked signed by their effects,
  :class:`~perga.machine.effects.ConstraintLosses`).
* ``energy_in_play`` = max(|drive_work|, |ΔKE + Δelastic|, |gravity_work|, ½Σ_i|ΔKE_i|,
  inflow, outflow, the granules' kinetic + elastic energy now and at t = 0, 1e-30 J), J: the
  work done and the energy the granules hold. ½Σ_i|ΔKE_i| (kinetic energy moved between
  bodies) keeps it meaningful where nothing is driven or lost (an elastic free impact,
  ΔKE = 0); the granules' energy where nothing has happened yet (granules fed in flight).
  The machine's own kinetic energy is not in it: a hammer carried round at constant speed
  holds tens of joules that nothing exchanges, and would hide a residual of the granules'
  scale (docs/dev/reliability.md).
* ``closure`` = residual / energy_in_play: what ``solver.ledger_tolerance`` judges. The
  residual itself (J) is kept beside it, so that a long run whose work done has grown large
  still shows its absolute error.

Costs per step: one compiled call (:func:`meter_step`: the constraint effects' losses, the
pins' work and the balance over the few rotor-driven bodies) on the machine's states before and
after the step (:meth:`~perga.machine.machine.Machine.state`, which the simulation also hands to
the contact model) and the pins' impulses in place, made by the Python step or inside the
compiled whole steps of a contact model; a loop over all bodies only when
:meth:`EnergyMeter.terms` is called.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pymunk

from perga.machine import units as u
from perga.machine.chipmunk_state import JointImpulses, doubles_at
from perga.machine.effects import ConstraintLosses, Drive, constraint_losses
from perga.machine.machine import Machine, MachineState
from perga.model.records import LedgerTerms

STATIC = -1
"""A pin's body row standing for the space's static body (:func:`_pivot_work`)."""


def _kinetic(body: pymunk.Body) -> float:
    """½m|v|² + ½Iω² (internal units); no rotational term for an infinite moment."""
    spin = 0.0 if body.moment == float("inf") else body.moment * body.angular_velocity**2
    return 0.5 * (body.mass * body.velocity.dot(body.velocity) + spin)


def _centre(body: pymunk.Body) -> pymunk.Vec2d:
    return body.local_to_world(body.center_of_gravity)


class EnergyMeter:
    """Measures the ledger's terms of a machine's bodies from the moment it is built (module
    doc).

    Call :meth:`before_step` and :meth:`after_step` around every ``space.step`` with the
    machine's states (:meth:`~perga.machine.machine.Machine.state`) then.
    """

    def __init__(self, machine: Machine) -> None:
        self._effects = machine.effects
        self._constraints = [e for e in machine.effects if isinstance(e, ConstraintLosses)]
        self._space = machine.space
        self._gravity = tuple(machine.space.gravity)
        """In-plane gravity, internal units (set when the machine is built, read once here)."""
        hinged = [j.b for j in machine.hinges]
        balanced = ([machine.rotor] if machine.driven else []) + hinged
        self._rows = np.array([machine.row_of(b) for b in balanced], dtype=np.int64)
        self._mass = np.array([b.mass for b in balanced], dtype=float)
        self._moment = np.array([b.moment for b in balanced], dtype=float)
        machine_bodies = dict.fromkeys([machine.rotor, *machine.hammer_bodies])
        self._bodies = [b for b in machine_bodies if b.body_type == pymunk.Body.DYNAMIC]
        self._needs_balance = bool(balanced or machine.rotor.shapes)
        self._kinetics0 = [_kinetic(b) for b in self._bodies]
        self._centres0 = [_centre(b) for b in self._bodies]
        axis = [e.pivot for e in machine.effects if isinstance(e, Drive)]
        self._pins = JointImpulses([*machine.hinges, *axis])
        self._pin_rows = np.array(
            [(machine.row_of(j.a), machine.row_of(j.b)) for j in machine.hinges]
            + [(machine.row_of(j.a), STATIC) for j in axis],
            dtype=np.int64,
        ).reshape(-1, 2)
        self._pin_arms = np.array(
            [tuple(j.anchor_b - j.b.center_of_gravity) for j in [*machine.hinges, *axis]],
            dtype=float,
        ).reshape(-1, 2)
        """Each pin's anchor on its body b from b's centre of gravity, b's frame (the static
        body's frame is the world's)."""
        self._totals = np.zeros(2)
        """The pins' work (joint correction) and the drive's work so far, internal units."""
        self._gx, self._gy = self._gravity
        self._before: MachineState | None = None

    def before_step(self, state: MachineState) -> None:
        """Keep the machine's ``state`` at the start of a step: read immediately before
        ``space.step`` (after anything else that changes velocities between steps)."""
        self._before = state

    def after_step(self, dt: float, contact_moment: float, state: MachineState) -> None:
        """Add the step's drive work and the constraint effects' losses; ``dt`` in internal time
        units, ``contact_moment`` the angular impulse about the axis that the contacts put on
        the rotor-driven bodies (the rotor, hinged and welded hammers) in this step, internal
        units; ``state`` the machine now."""
        before = self._before
        assert before is not None, "after_step without before_step"
        meter_step(self.compiled(dt), before.table, state.table, contact_moment)

    def compiled(self, dt: float) -> tuple:
        """The arguments of :func:`meter_step` but the states and the contacts' moment, for
        steps of ``dt`` (internal time units)."""
        losses = tuple(effect.losses() for effect in self._constraints)
        losses += (_NO_LOSS,) * (CONSTRAINT_EFFECTS - len(losses))
        return (
            losses, self._pin_rows, self._pin_arms, self._pins.addresses(), self._rows,
            self._mass, self._moment, self._gx * dt, self._gy * dt,
            self._needs_balance or bool(self._pin_rows.size), self._needs_balance, self._totals,
        )  # fmt: skip

    def terms(self) -> LedgerTerms:
        """The cumulative terms of the machine's bodies and the effects now, in J."""
        gravity = self._space.gravity
        kinetics = [_kinetic(b) for b in self._bodies]
        terms = {"friction": 0.0, "drag": 0.0, "drive": 0.0, "contact": 0.0}
        supplied = 0.0
        for effect in self._effects:
            terms[effect.term] += effect.removed
            supplied += effect.supplied
        return LedgerTerms(
            kinetic=sum(kinetics) * u.ENERGY,
            kinetic_initial=sum(self._kinetics0) * u.ENERGY,
            moved=0.5
            * sum(abs(k - k0) for k, k0 in zip(kinetics, self._kinetics0, strict=True))
            * u.ENERGY,
            drive_work=float(self._totals[1]) * u.ENERGY + supplied,
            gravity_work=sum(
                b.mass * gravity.dot(_centre(b) - r0)
                for b, r0 in zip(self._bodies, self._centres0, strict=True)
            )
            * u.ENERGY,
            contact_dissipation=terms["contact"],
            friction=terms["friction"],
            drag=terms["drag"],
            joint_correction=float(self._totals[0]) * u.ENERGY,
        )


CONSTRAINT_EFFECTS = len(ConstraintLosses.__subclasses__())
"""The constraint effects a machine can have, one of each kind (hinge friction, swing stops):
the compiled meter always takes that many constraint losses, those of the effects a machine
lacks empty, so that it (and the machine steps that call it) compiles once for every machine."""
_NO_LOSS = (np.zeros(2), np.zeros(0, dtype=np.uint64), np.zeros((0, 2), dtype=np.int64))
"""The constraint losses' arguments of an effect a machine lacks: no constraint."""

IDLE_METER = (
    (_NO_LOSS,) * CONSTRAINT_EFFECTS, np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2)),
    np.zeros(0, dtype=np.uint64), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0), 0.0,
    0.0, False, False, np.zeros(2),
)  # fmt: skip
""":meth:`EnergyMeter.compiled`'s arguments where no meter runs (compiled code that may meter
takes a meter of this type; a run without one books nothing in it)."""


@numba.njit(cache=True)
def meter_step(meter: tuple, before: np.ndarray, after: np.ndarray, contact_moment: float) -> None:
    """One step's terms (:meth:`EnergyMeter.after_step`) in compiled code, ``meter`` being
    :meth:`EnergyMeter.compiled`'s: each constraint effect's losses
    (:func:`~perga.machine.effects.constraint_losses`), then, where there are pins or a balance,
    the pins' work and, with a balance, the drive's work added to the totals."""
    losses, pin_rows, pin_arms, pins, rows, mass, moment, gx_dt, gy_dt, terms, balance, totals = (
        meter
    )
    for energy, impulses, constraint_rows in losses:
        constraint_losses(energy, impulses, constraint_rows, before, after)
    if not terms:
        return
    work, change = _machine_terms(
        before, after, pin_rows, pin_arms, pins, rows, mass, moment, gx_dt, gy_dt
    )
    totals[0] += work
    if balance:
        totals[1] += 0.5 * (before[0, 5] + after[0, 5]) * (change - contact_moment)


@numba.njit(cache=True)
def _machine_terms(
    before: np.ndarray,
    after: np.ndarray,
    pin_rows: np.ndarray,
    pin_arms: np.ndarray,
    impulses: np.ndarray,
    rows: np.ndarray,
    mass: np.ndarray,
    moment: np.ndarray,
    gx_dt: float,
    gy_dt: float,
) -> tuple[float, float]:
    """The step's terms from two machine-state tables (:class:`~perga.machine.machine.
    MachineState`): the pins' work (:func:`_pivot_work`, pin k's jAcc at ``impulses[k]``)
    and the angular impulse on the bodies at ``rows`` besides gravity's
    (:func:`_moment_change`)."""
    return (
        _pivot_work(before, after, pin_rows, pin_arms, impulses),
        _moment_change(before, after, rows, mass, moment, gx_dt, gy_dt),
    )


@numba.njit(cache=True)
def _moment_change(
    before: np.ndarray,
    after: np.ndarray,
    rows: np.ndarray,
    mass: np.ndarray,
    moment: np.ndarray,
    gx_dt: float,
    gy_dt: float,
) -> float:
    """Σ m r × (v_after − v_before − g dt) + I (ω_after − ω_before) about the axis over the
    bodies at ``rows`` of two machine-state tables (:class:`~perga.machine.machine.MachineState`):
    the angular impulse that acted on them in the step, besides gravity's."""
    total = 0.0
    for j in range(rows.size):
        k = rows[j]
        dvx = after[k, 3] - before[k, 3] - gx_dt
        dvy = after[k, 4] - before[k, 4] - gy_dt
        total += mass[j] * (after[k, 0] * dvy - after[k, 1] * dvx)
        total += moment[j] * (after[k, 5] - before[k, 5])
    return total


@numba.njit(cache=True)
def _pivot_work(
    before: np.ndarray,
    after: np.ndarray,
    rows: np.ndarray,
    arms: np.ndarray,
    impulses: np.ndarray,
) -> float:
    """Σ J·(v̄_b − v̄_a) over pivot joints: the work their position correction did in a step
    (an ideal pin does none). Joint k joins the bodies at ``rows[k]`` = (a, b) of two
    machine-state tables, b = :data:`STATIC` for the static body (at rest, its frame the
    world's); J, the two doubles at the address ``impulses[k]`` (:meth:`~perga.engine.
    chipmunk_state.JointImpulses.addresses`), acts on b at its anchor, ``arms[k]`` from b's
    centre of gravity in b's frame; v̄ is each body's velocity at that point, the mean of
    before and after the step, at the lever arm of the step's new positions (where Chipmunk
    applies the impulse)."""
    total = 0.0
    for k in range(rows.shape[0]):
        a, b = rows[k, 0], rows[k, 1]
        if b == STATIC:
            rax, ray = arms[k, 0] - after[a, 0], arms[k, 1] - after[a, 1]
            vbx = vby = 0.0
        else:
            cos, sin = math.cos(after[b, 2]), math.sin(after[b, 2])
            rbx = cos * arms[k, 0] - sin * arms[k, 1]
            rby = sin * arms[k, 0] + cos * arms[k, 1]
            rax = after[b, 0] + rbx - after[a, 0]
            ray = after[b, 1] + rby - after[a, 1]
            wb = 0.5 * (before[b, 5] + after[b, 5])
            vbx = 0.5 * (before[b, 3] + after[b, 3]) - wb * rby
            vby = 0.5 * (before[b, 4] + after[b, 4]) + wb * rbx
        wa = 0.5 * (before[a, 5] + after[a, 5])
        vax = 0.5 * (before[a, 3] + after[a, 3]) - wa * ray
        vay = 0.5 * (before[a, 4] + after[a, 4]) + wa * rax
        j = doubles_at(impulses[k], 2)
        total += j[0] * (vbx - vax) + j[1] * (vby - vay)
    return total
