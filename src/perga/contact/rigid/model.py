"""Rigid contacts: granules as Pymunk bodies whose contacts are Chipmunk's impulses, restitution
and friction exact per impact (:class:`RigidContacts`).

The granules move in the machine's own ``space.step`` (drift, collision detection, impulses:
:mod:`perga.engine.simulation`); the model adds them, the chamber wall and the collision
handlers to the machine's space (:mod:`~perga.contact.rigid.bodies`), replaces the contacts of
hammers of several pieces by their outline's (:mod:`~perga.contact.rigid.outline`), keeps
granule-wall bounces under gravity to the impulse law (:mod:`~perga.contact.rigid.wall_bounce`),
moves the contacts of granules that do not roll onto their centres
(:mod:`~perga.contact.rigid.sliding_point`), records the impacts
(:mod:`~perga.contact.rigid.impacts`) and measures what the contacts dissipate
(:mod:`~perga.contact.rigid.dissipation`).

A held granule (a comb's cell: ``GranuleSpec.bond_force``) moves freely within a machine step,
so that a hammer strikes a granule of its own mass; after the step its bond must supply the
impulse m·|v| that brings it back to rest, a force F = m·|v|/dt. While F is at most the bond's
force, the granule is set back at rest in its cell (for a static load such as gravity the force
is the load itself, exactly). At the first step where it is larger, a bond without energy
breaks, having taken the most it can, bond·dt, from the granule's momentum; a bond with an
energy E_c (``GranuleSpec.bond_energy``) that can carry the granule's weight (m|g| at most its
force) sees the step as a blow, over within the step (an
impulse): if the granule's kinetic energy E (translation and spin) exceeds E_c the bond breaks
and the granule goes on with its velocities scaled by √(1 − E_c/E), else the granule stops where
it is, its new cell (as in the soft kernel, ``perga.contact.soft.kernel``). The kinetic energy
the bonds take is part of the contacts' dissipation (the cell is a contact).
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pymunk

from perga.contact.protocol import FloatArray, GranuleState
from perga.contact.rigid import sliding_point
from perga.contact.rigid.bodies import attach_bodies
from perga.contact.rigid.dissipation import ArbiterMeter
from perga.contact.rigid.impacts import RigidImpactLog
from perga.contact.rigid.outline import OutlineFilter
from perga.contact.rigid.wall_bounce import wall_bounce
from perga.machine import units as u
from perga.machine.batch import BodyReader, BodyWriter
from perga.machine.effects import FloorKick
from perga.machine.machine import Machine, MachineState
from perga.model.records import Contact, Impact, LedgerTerms, Release
from perga.model.system import GranuleSpec

if TYPE_CHECKING:
    from perga.machine.compiled import CompiledMachine


@dataclass
class _Bond:
    """A held granule's bond: its cell (internal units), force (N) and energy (J, inf: none;
    module doc)."""

    cell: FloatArray
    force: float
    energy: float


class _Kinematics:
    """The granule bodies' velocities for the kicks, read from the space in internal units (a
    writer rebuilt when granules change)."""

    def __init__(self, model: RigidContacts) -> None:
        self._model = model

    @property
    def count(self) -> int:
        return len(self._model.ids)

    def constants(self) -> tuple[FloatArray, FloatArray]:
        return self._model.masses, self._model.radii

    def read(self, *, positions: bool) -> tuple[FloatArray, FloatArray | None]:
        velocities, where = self._model.writer().read_internal(positions=positions)
        return velocities * u.VELOCITY, None if where is None else where * u.LENGTH

    def write_velocities(self, velocities: FloatArray) -> None:
        self._model.writer().write_internal_velocities(velocities / u.VELOCITY)

    def take_floor_kick(self, kick: FloorKick) -> bool:
        return False  # the runner's batch read and write serve the bodies


class RigidContacts:
    """The rigid contact model on ``machine`` (:class:`~perga.contact.protocol.ContactModel`).

    record_impacts: keep an :class:`~perga.model.records.Impact` per granule-hammer impact;
    track_energy: measure the contacts' dissipation (from the simulation's two reads of the
    space and one arbiter read per step, no Python callback). Per granule row: ``ids``
    (persistent numbers), ``masses`` (kg), ``radii`` (m).
    """

    def __init__(
        self, machine: Machine, *, record_impacts: bool = True, track_energy: bool = True
    ) -> None:
        spec = machine.spec
        self.machine = machine
        self.bodies = attach_bodies(machine, spec.granule_materials)
        self.granule_dt = spec.granule_dt
        self.threads = 1  # Chipmunk steps on one thread
        outline = OutlineFilter(machine)  # hammers of several pieces: their outline's contacts
        if outline:
            self.bodies.listen("pre_solve", outline.pre_solve, ("granule", "hammer"))
        if any(spec.gravity):  # after the pair setters, which set the pair's restitution
            self.bodies.listen("pre_solve", wall_bounce, ("granule", "wall"))
        feed = spec.process.feed
        rolls = {g.rolls for g in spec.granules} | ({feed.rolls} if feed is not None else set())
        sliding = False in rolls
        if sliding:
            self.bodies.listen("pre_solve", sliding_point.hammer_contact, ("granule", "hammer"))
        if rolls == {True, False}:  # two sliding points need nothing (sliding_point)
            self.bodies.listen("pre_solve", sliding_point.granule_contact, ("granule", "granule"))
        self._bonds: dict[int, _Bond] = {}
        self.log = (
            RigidImpactLog(self.bodies, self._bonds, rewritten=bool(outline) or sliding)
            if record_impacts
            else None
        )
        self.arbiters = ArbiterMeter(machine) if track_energy else None
        self.releases: list[Release] = []
        self.ids = np.arange(len(spec.granules), dtype=np.int64)
        self.masses = np.array([g.mass for g in spec.granules], dtype=float)
        self.radii = np.array([g.radius for g in spec.granules], dtype=float)
        self._moments = np.array([g.moment if g.rolls else 0.0 for g in spec.granules])
        """Held granules by id: their cell (internal units) and bond force (N)."""
        self._bond_loss = 0.0  # J
        self._reader: BodyReader | None = None
        self._writer: BodyWriter | None = None
        self._kinematics = _Kinematics(self)
        self._dt = spec.machine_dt
        self._gravity = np.asarray(spec.gravity, dtype=float)
        self._x0 = np.array([g.position for g in spec.granules], dtype=float).reshape(-1, 2)
        self._energy0 = self._energies(self.granule_state())
        self._kinetic0 = float(self._energy0.sum())
        self._gone = LedgerTerms()  # the terms of granules removed, frozen at their removal
        self._inflow = 0.0
        for id_, (g, body) in enumerate(
            zip(spec.granules, self.bodies.granule_bodies, strict=True)
        ):
            if g.bond_force is not None:
                self._hold(id_, body, g)

    # --- the protocol ------------------------------------------------------------------------

    @property
    def impacts(self) -> list[Impact]:
        """Impacts recorded so far (empty if recording is off)."""
        return [] if self.log is None else self.log.impacts

    @property
    def contact_episodes(self) -> list[Contact]:
        """Granule-hammer contacts ended so far (empty if recording is off)."""
        return [] if self.log is None else self.log.contacts

    def running(self) -> AbstractContextManager[None]:
        """Nothing to hold over a run: Chipmunk steps on one thread."""
        return nullcontext()

    def kinematics(self) -> _Kinematics:
        """The granule bodies' velocities, read and written in one ``pymunk.batch`` pass each."""
        return self._kinematics

    def writer(self) -> BodyWriter:
        """The batch writer of the granules present (rebuilt after a change)."""
        if self._writer is None:
            self._writer = BodyWriter(self.machine.space, self.bodies.granule_bodies)
        return self._writer

    def before_machine_step(self, time: float, machine: MachineState) -> None:
        """Stamp the step's impacts with its end ``time`` (s); keep the bodies' velocities for
        the dissipation."""
        if self.log is not None:
            self.log.time = time
        if self.arbiters is not None:
            self.arbiters.before_step()

    def after_machine_step(self, time: float, machine: MachineState) -> float:
        """The step's dissipation from the arbiters (read before anything moves a body); release
        the held granules whose bond is overloaded; returns the arbiters' angular impulse about
        the axis on the rotor-driven bodies, internal units."""
        self.bodies.raise_errors()
        moment = 0.0 if self.arbiters is None else self.arbiters.after_step()
        if self._bonds:
            self._hold_or_release(time)
        return moment

    def machine_steps(self, limit: int, machine: CompiledMachine) -> int:
        """No compiled steps (0): the impulse contacts are Chipmunk's collision handlers, Python
        callbacks."""
        return 0

    def energy_terms(self) -> LedgerTerms:
        """The granules' kinetic energy, gravity's work on them, what fed and removed granules
        brought and took, and the contacts' dissipation, J."""
        state = self.granule_state()
        energies = self._energies(state)
        present = LedgerTerms(
            kinetic=float(energies.sum()),
            kinetic_initial=self._kinetic0,
            moved=0.5 * float(np.abs(energies - self._energy0).sum()),
            gravity_work=self._gravity_work(state),
            contact_dissipation=self._bond_loss
            + (0.0 if self.arbiters is None else self.arbiters.dissipated * u.ENERGY),
            inflow=self._inflow,
        )
        return present + self._gone

    def granule_state(self) -> GranuleState:
        """The granules now, SI (one ``pymunk.batch`` read)."""
        p, v, w = self._granule_reader().read()
        held = np.isin(self.ids, list(self._bonds)) if self._bonds else np.zeros(len(p), bool)
        return GranuleState(
            p,
            v,
            w,
            self.ids.copy(),
            self.radii.copy(),
            self.masses.copy(),
            self._moments.copy(),
            held,
        )

    def contact_counts(self) -> None:
        """Impulses have no overlap: None."""
        return None

    def add_granules(self, granules: Sequence[GranuleSpec], ids: Sequence[int]) -> None:
        """Add granules with these ids (held ones in their cells)."""
        for g, id_ in zip(granules, ids, strict=True):
            body = self.bodies.add_granule(g, int(id_))
            if g.bond_force is not None:
                self._hold(int(id_), body, g)
        new = list(granules)
        self.ids = np.append(self.ids, np.asarray(ids, dtype=np.int64))
        self.masses = np.append(self.masses, [g.mass for g in new])
        self.radii = np.append(self.radii, [g.radius for g in new])
        self._moments = np.append(self._moments, [g.moment if g.rolls else 0.0 for g in new])
        self._x0 = np.vstack([self._x0, np.array([g.position for g in new]).reshape(-1, 2)])
        energy = np.array(
            [
                0.5 * g.mass * (g.velocity[0] ** 2 + g.velocity[1] ** 2)
                + 0.5 * (g.moment if g.rolls else 0.0) * g.angular_velocity**2
                for g in new
            ]
        )
        self._energy0 = np.append(self._energy0, energy)
        self._inflow += float(energy.sum())
        self._changed()

    def remove_granules(self, ids: Sequence[int]) -> None:
        """Take these granules out, booking their energy and gravity's work on them."""
        rows = np.flatnonzero(np.isin(self.ids, np.asarray(ids, dtype=np.int64)))
        if rows.size == 0:
            return
        state = self.granule_state()
        energies = self._energies(state)
        keep = np.ones(len(self.ids), dtype=bool)
        keep[rows] = False
        gone = LedgerTerms(
            moved=0.5 * float(np.abs(energies[rows] - self._energy0[rows]).sum()),
            gravity_work=float(
                np.sum(
                    self.masses[rows] * ((state.positions[rows] - self._x0[rows]) @ self._gravity)
                )
            ),
            outflow=float(energies[rows].sum()),
        )
        self._gone = self._gone + gone
        for id_ in self.ids[rows]:
            self._bonds.pop(int(id_), None)
        self.bodies.remove_granules([int(r) for r in rows])
        for name in ("ids", "masses", "radii", "_moments", "_x0", "_energy0"):
            setattr(self, name, getattr(self, name)[keep])
        self._changed()

    # --- internals ---------------------------------------------------------------------------

    def _granule_reader(self) -> BodyReader:
        """The batch reader of the granules present (rebuilt after a change)."""
        if self._reader is None:
            self._reader = BodyReader(self.machine.space, self.bodies.granule_bodies)
        return self._reader

    def _changed(self) -> None:
        self._reader = self._writer = None

    def _energies(self, state: GranuleState) -> FloatArray:
        v2 = np.sum(state.velocities**2, axis=1)
        return 0.5 * state.masses * v2 + 0.5 * state.inertia * state.angular_velocities**2

    def _gravity_work(self, state: GranuleState) -> float:
        return float(np.sum(self.masses * ((state.positions - self._x0) @ self._gravity)))

    def _hold(self, id_: int, body: pymunk.Body, granule: GranuleSpec) -> None:
        """Hold ``body`` in its cell where it is, with the granule's bond."""
        assert granule.bond_force is not None
        self._bonds[id_] = _Bond(
            np.array(body.position, dtype=float), granule.bond_force, granule.bond_energy
        )

    def _hold_or_release(self, time: float) -> None:
        """Set the held granules back at rest in their cells, or end the blows of those whose
        bond the step overloaded (module doc); book the kinetic energy the bonds took.

        "At rest" is the velocity that brings a granule back to its cell over the next step,
        (cell − x)/dt (Chipmunk moves bodies before it applies gravity and impulses; 0 unless
        the granule moved), so that held granules do not creep and one batch write of
        velocities does.
        """
        writer = self.writer()
        v, x = writer.read_internal(positions=True)
        assert x is not None
        held = np.fromiter(self._bonds, dtype=np.int64, count=len(self._bonds))
        rows = np.searchsorted(self.ids, held)  # ids stay ascending: appended, never reordered
        records = [self._bonds[int(i)] for i in held]
        cells = np.array([b.cell for b in records]).reshape(-1, 2)
        bonds = np.array([b.force for b in records])
        capacity = np.array([b.energy for b in records])
        mass = self.masses[rows]
        speed = np.hypot(*(v[rows] * u.VELOCITY).T)
        spins = self._granule_reader().angular_velocities()[rows]
        moments = self._moments[rows]
        force = mass * speed / self._dt
        kept = force <= bonds
        energy = 0.5 * (mass * speed**2 + moments * spins**2)
        blow = ~kept & np.isfinite(capacity) & (mass * np.hypot(*self._gravity) <= bonds)
        broken = ~kept & ((energy > capacity) | ~blow)
        stopped = blow & ~broken
        share = np.ones(len(held))
        forced = broken & ~blow
        share[forced] = 1.0 - bonds[forced] * self._dt / np.maximum(mass * speed, 1e-300)[forced]
        struck = broken & blow
        share[struck] = np.sqrt(1.0 - capacity[struck] / energy[struck])
        rest = (cells - x[rows]) / (self._dt / u.TIME)
        new = v[rows] * share[:, None]
        new[kept] = rest[kept]
        new[stopped] = 0.0
        spin_share = np.where(struck, share, np.where(broken, 1.0, 0.0))
        after = 0.5 * (
            mass * np.sum((new * u.VELOCITY) ** 2, axis=1) + moments * (spins * spin_share) ** 2
        )
        self._bond_loss += float(np.sum(energy - after))
        v[rows] = new
        writer.write_internal_velocities(v)
        for i in np.flatnonzero(stopped):
            records[i].cell = x[rows[i]].copy()
        for i in np.flatnonzero(spins * (1.0 - spin_share) != 0.0):
            body = self.bodies.granule_bodies[rows[i]]
            body.angular_velocity = spins[i] * spin_share[i] / u.ANGULAR_VELOCITY
        for i in np.flatnonzero(broken):
            del self._bonds[int(held[i])]
            self.releases.append(Release(time, int(held[i]), float(force[i])))
