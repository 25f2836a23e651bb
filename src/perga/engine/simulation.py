"""The one simulation: a machine (rotor, hammers, joints, effects in Pymunk) and a contact model
(the granules and their contacts, :mod:`perga.contact`), stepped together.

Step order of :meth:`Simulation.step` (one machine step dt, t_n -> t_{n+1}; dt =
``SceneSpec.machine_dt``, the granules take ``contact_model.substeps`` steps of
``SceneSpec.granule_dt`` inside it):

1. Kicks: only if the spec lists them, floor friction and air drag change all granules'
   velocities at once from (x_n, v_n) (:mod:`perga.engine.effects`): an operator split before
   everything else, so the contacts and the drift see the kicked velocities.
2. The contact model's work before the machine moves
   (:meth:`~perga.contact.protocol.ContactModel.before_machine_step`): rigid, nothing moves
   yet (the granules are bodies of the space); soft, the kernel advances the granules over the
   step against the hammers posed ahead and loads the hammer bodies with the mean contact force.
3. The energy meter records the rotor-driven bodies' velocities.
4. Chipmunk's step of the space: positions and angles advance with the current velocities
   (the kinematic rotor turns by ω·dt), collision detection at the new positions (rigid
   contacts call their handlers: the impact recorder's start, the pair setters, the outline
   filter), gravity and the bodies' forces are added to the velocities, and the impulse solver
   runs ``iterations`` times over contacts and joints (``post_solve``: impacts completed).
5. The contact model's work after it
   (:meth:`~perga.contact.protocol.ContactModel.after_machine_step`): rigid, the arbiters'
   dissipation; soft, the impact log. It returns the contacts' angular impulse on the
   rotor-driven bodies, which the meter needs for the drive's work.
6. The meter balances the rotor-driven bodies' angular momentum (:mod:`perga.engine.energy`).
7. The step counter is incremented; ``time`` is n·dt from the integer count (no drift).

Because positions move before velocities are updated (step 4), the state after a step is
(x_{n+1}, v_{n+1}) with v_{n+1} computed from the forces at x_{n+1}: symplectic Euler, first
order; in leapfrog terms the velocities are half a step ahead of the positions. Soft granules
and the hammers they load form one kick-drift scheme (docs/architecture.md).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from perga.contact import contact_model
from perga.contact.protocol import ContactModel
from perga.engine import units as u
from perga.engine.effects import KickRunner
from perga.engine.energy import EnergyMeter
from perga.engine.machine import Machine, build_machine
from perga.model.frame import Frame, GranuleFrame, frozen
from perga.model.records import EnergyLedger, Impact
from perga.model.spec import SceneSpec

FloatArray = NDArray[np.float64]


class Simulation:
    """Steps the system ``spec`` at its machine step (module doc for the order).

    ``machine`` is the Pymunk side, ``contacts`` the contact model the spec names
    (:data:`perga.contact.MODELS`). record_impacts: keep an
    :class:`~perga.model.records.Impact` per granule-hammer impact; track_energy: measure the
    energy ledger from now on.
    """

    def __init__(
        self, spec: SceneSpec, *, record_impacts: bool = True, track_energy: bool = True
    ) -> None:
        self.spec = spec
        self.dt = spec.machine_dt
        """The step of :meth:`step`, s."""
        self.steps = 0
        self._dt_internal = u.to_internal(self.dt, u.TIME)
        self.machine: Machine = build_machine(spec)
        model = contact_model(spec.contact_model.kind)
        self.contacts: ContactModel = model(
            self.machine, record_impacts=record_impacts, track_energy=track_energy
        )
        kicks = KickRunner(self.machine.effects, self.contacts.kinematics())
        self.kicks = kicks if kicks else None
        """The effects' kicks on the granules (None when the spec lists none)."""
        self.meter = EnergyMeter(self.machine) if track_energy else None
        self._constants: GranuleFrame | None = None

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.steps * self.dt

    @property
    def impacts(self) -> list[Impact]:
        """Impacts recorded so far (empty if recording is off)."""
        return self.contacts.impacts

    def step(self) -> None:
        """Advance by one machine step dt."""
        end = (self.steps + 1) * self.dt
        if self.kicks is not None:
            self.kicks.run(self._dt_internal)
        self.contacts.before_machine_step(end)
        if self.meter is not None:
            self.meter.before_step()
        self.machine.space.step(self._dt_internal)
        moment = self.contacts.after_machine_step(end)
        if self.meter is not None:
            self.meter.after_step(self._dt_internal, moment)
        self.steps += 1

    def run(self, duration: float) -> int:
        """Advance by ``duration`` (s), rounded to a whole number of steps; returns the count."""
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0 s (got {duration})")
        n = round(duration / self.dt)
        for _ in range(n):
            self.step()
        return n

    def energy(self) -> EnergyLedger:
        """The energy ledger since the simulation was created (J; needs ``track_energy``)."""
        if self.meter is None:
            raise RuntimeError("energy() needs Simulation(..., track_energy=True)")
        return (self.meter.terms() + self.contacts.energy_terms()).close()

    def frame(self, *, contacts: bool = True) -> Frame:
        """The simulation now as a :class:`~perga.model.frame.Frame` (with the ledger when
        energy is tracked; with the granules' contact counts where the contact model has them,
        unless ``contacts`` is False)."""
        state = self.contacts.granule_state()
        counts = self.contacts.contact_counts() if contacts else None
        constants = self._granule_constants()
        granules = GranuleFrame(
            ids=constants.ids,
            radii=constants.radii,
            masses=constants.masses,
            inertia=constants.inertia,
            materials=constants.materials,
            material_names=constants.material_names,
            positions=frozen(state.positions),
            velocities=frozen(state.velocities),
            angular_velocities=frozen(state.angular_velocities),
            contacts=None if counts is None else frozen(counts[0]),
            overlap_max=None if counts is None else frozen(counts[1]),
        )
        return Frame(
            time=self.time,
            step=self.steps,
            granules=granules,
            machine=self.machine.frame(self.dt),
            energy=None if self.meter is None else self.energy(),
        )

    def _granule_constants(self) -> GranuleFrame:
        """The granules' constant arrays (built once; their state arrays left empty)."""
        if self._constants is None:
            granules = self.spec.granules
            names = tuple(sorted({g.material for g in granules}))
            empty = frozen(np.zeros((0, 2)))
            self._constants = GranuleFrame(
                ids=frozen(np.arange(len(granules), dtype=np.int64)),
                radii=frozen(np.array([g.radius for g in granules], dtype=float)),
                masses=frozen(np.array([g.mass for g in granules], dtype=float)),
                inertia=frozen(np.array([g.moment if g.rolls else 0.0 for g in granules])),
                materials=frozen(
                    np.array([names.index(g.material) for g in granules], dtype=np.int32)
                ),
                material_names=names,
                positions=empty,
                velocities=empty,
                angular_velocities=frozen(np.zeros(0)),
            )
        return self._constants

    # --- state in SI ---------------------------------------------------------------------------

    def granule_positions(self) -> FloatArray:
        """Granule centres, (n, 2) array, m."""
        return self.contacts.granule_state().positions

    def granule_velocities(self) -> FloatArray:
        """Granule centre velocities, (n, 2) array, m/s."""
        return self.contacts.granule_state().velocities

    def granule_angular_velocities(self) -> FloatArray:
        """Granule angular velocities, (n,) array, rad/s."""
        return self.contacts.granule_state().angular_velocities

    def rotor_angle(self) -> float:
        """Rotor angle, rad (ω·t at constant ω)."""
        return float(self.machine.rotor.angle)

    def rotor_angular_velocity(self) -> float:
        """Rotor angular velocity, rad/s (varies only with a driven rotor)."""
        return float(self.machine.rotor.angular_velocity) * u.ANGULAR_VELOCITY

    def hammer_swing_angles(self) -> FloatArray:
        """α of each hammer: its axis angle relative to the radial line through the hinge on
        the turning rotor, rad (constant for welded hammers)."""
        return self.machine.frame(self.dt).swing_angles.copy()

    def hammer_angular_velocities(self) -> FloatArray:
        """Absolute angular velocity of each hammer, (n,) array, rad/s (welded: the rotor's)."""
        return self.machine.frame(self.dt).angular_velocities.copy()

    def hammer_velocities(self) -> FloatArray:
        """Centre-of-mass velocity of each hammer, (n, 2) array, m/s (welded: the rotor's
        velocity at the hammer's centre of mass)."""
        return self.machine.frame(self.dt).velocities.copy()
