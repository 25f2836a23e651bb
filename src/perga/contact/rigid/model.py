"""Rigid contacts: granules as Pymunk bodies whose contacts are Chipmunk's impulses, restitution
and friction exact per impact (:class:`RigidContacts`).

The granules move in the machine's own ``space.step`` (drift, collision detection, impulses:
:mod:`perga.engine.simulation`); the model adds them, the chamber wall and the collision
handlers to the machine's space (:mod:`~perga.contact.rigid.bodies`), replaces the contacts of
hammers of several pieces by their outline's (:mod:`~perga.contact.rigid.outline`), records the
impacts (:mod:`~perga.contact.rigid.impacts`) and measures what the contacts dissipate
(:mod:`~perga.contact.rigid.dissipation`). The granules' kinetic energy and gravity's work on
them are the machine meter's, as for every body of the space (:mod:`perga.engine.energy`).
"""

from __future__ import annotations

from perga.contact.protocol import GranuleState
from perga.contact.rigid.batch import GranuleReader, GranuleWriter
from perga.contact.rigid.bodies import attach_bodies
from perga.contact.rigid.dissipation import ArbiterMeter
from perga.contact.rigid.impacts import ImpactRecorder
from perga.contact.rigid.outline import OutlineFilter
from perga.engine import units as u
from perga.engine.machine import Machine
from perga.model.records import Impact, LedgerTerms


class RigidContacts:
    """The rigid contact model on ``machine`` (:class:`~perga.contact.protocol.ContactModel`).

    record_impacts: keep an :class:`~perga.model.records.Impact` per granule-hammer impact;
    track_energy: measure the contacts' dissipation (two ``pymunk.batch`` body reads and one
    arbiter read per step, no Python callback).
    """

    def __init__(
        self, machine: Machine, *, record_impacts: bool = True, track_energy: bool = True
    ) -> None:
        self.machine = machine
        self.bodies = attach_bodies(machine)
        self.granule_dt = machine.spec.granule_dt
        outline = OutlineFilter(machine)  # hammers of several pieces: their outline's contacts
        if outline:
            self.bodies.listen("pre_solve", outline.pre_solve, ("granule", "hammer"))
        self.recorder = (
            ImpactRecorder(self.bodies, filtered=bool(outline)) if record_impacts else None
        )
        self.arbiters = ArbiterMeter(machine) if track_energy else None
        self._reader: GranuleReader | None = None
        self._writer: GranuleWriter | None = None

    @property
    def impacts(self) -> list[Impact]:
        """Impacts recorded so far (empty if recording is off)."""
        return [] if self.recorder is None else self.recorder.impacts

    def kinematics(self) -> GranuleWriter:
        """The granule bodies' velocities, read and written in one ``pymunk.batch`` pass each."""
        if self._writer is None:
            self._writer = GranuleWriter(self.machine.space, self.bodies.granule_bodies)
        return self._writer

    def before_machine_step(self, time: float) -> None:
        """Stamp the step's impacts with its end ``time`` (s); read the bodies' velocities for
        the dissipation."""
        if self.recorder is not None:
            self.recorder.time = time
        if self.arbiters is not None:
            self.arbiters.before_step()

    def after_machine_step(self, time: float) -> float:
        """The step's dissipation from the arbiters; returns their angular impulse about the axis
        on the rotor-driven bodies, internal units."""
        return 0.0 if self.arbiters is None else self.arbiters.after_step()

    def energy_terms(self) -> LedgerTerms:
        """The contacts' dissipation, J (the granules' other terms are the machine meter's)."""
        if self.arbiters is None:
            return LedgerTerms()
        return LedgerTerms(contact_dissipation=self.arbiters.dissipated * u.ENERGY)

    def granule_state(self) -> GranuleState:
        """Positions, velocities and spins now, SI (one ``pymunk.batch`` read)."""
        if self._reader is None:
            self._reader = GranuleReader(self.machine.space, self.bodies.granule_bodies)
        return self._reader.read()

    def contact_counts(self) -> None:
        """Impulses have no overlap: None."""
        return None
