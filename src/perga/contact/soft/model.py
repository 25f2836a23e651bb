"""Soft contacts: granules as arrays stepped by perga's numba kernel beside Pymunk's rotor and
hammers, with linear or Hertz spring-dashpot contacts tuned to each pair's restitution
(:class:`SoftContacts`).

Per machine step (``machine_dt`` = k granule steps; the whole order is in
:mod:`perga.engine.simulation`):

* before Chipmunk's step: each hammer is posed one granule step ahead along its current motion
  (:mod:`perga.contact.soft.machine` explains why); the kernel takes k granule steps in one
  compiled call (:mod:`perga.contact.soft.kernel`), which first applies floor friction (the
  effects hand its kick over: :class:`~perga.machine.effects.FloorKick`) and keeps the state
  after it for the impact log: pair, wall and hammer contacts, kick-drift;
  hammers move rigidly with their current velocities during the call and the mean load on
  each becomes its body's force and torque for Chipmunk's step;
* after it: the impact log opens and closes granule-hammer impacts
  (:mod:`perga.contact.soft.impacts`), and the loads' moment about the axis over the step is
  handed to the energy meter.

Energy: the model's ledger terms are the granules' kinetic energy, the elastic energy stored in
their contacts, the work of in-plane gravity on them, and the energy the contacts dissipated,
measured by the kernel from the contact law itself (dashpots, Coulomb slip, rolling
resistance), not as a balance: the closure stays a real check.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from contextlib import AbstractContextManager
from time import monotonic
from typing import TYPE_CHECKING

import numpy as np
import pymunk

from perga.contact.protocol import FloatArray, GranuleState
from perga.contact.soft.build import granule_table_materials, soft_granules
from perga.contact.soft.granules import opening_of
from perga.contact.soft.impacts import SoftImpactLog
from perga.contact.soft.kernel import COUNT_RELEASES
from perga.contact.soft.machine import MachinePolygons
from perga.contact.soft.machine_steps import machine_steps
from perga.contact.soft.threads import RECHECK, kernel_chunks, kernel_threads, numba_threads
from perga.cores import CoreMonitor
from perga.machine import units as u
from perga.machine.effects import FloorKick
from perga.machine.machine import Machine, MachineState
from perga.model.records import Contact, Impact, LedgerTerms, Release
from perga.model.system import GranuleSpec

if TYPE_CHECKING:
    from perga.machine.compiled import CompiledMachine

ANGULAR_IMPULSE = u.FORCE * u.LENGTH * u.TIME
"""N·m·s per internal angular impulse unit."""


class _Kinematics:
    """The soft granules' velocities for the kicks: the kernel's own arrays, SI; floor friction
    taken over by ``model`` (applied in its kernel call)."""

    def __init__(self, model: SoftContacts) -> None:
        self._model = model
        self._g = model.granules

    @property
    def count(self) -> int:
        return self._g.n

    def constants(self) -> tuple[FloatArray, FloatArray]:
        return self._g.m, self._g.r

    def read(self, *, positions: bool) -> tuple[FloatArray, FloatArray | None]:
        return self._g.v, self._g.x if positions else None

    def write_velocities(self, velocities: FloatArray) -> None:
        if velocities is not self._g.v:
            self._g.v[:] = velocities

    def take_floor_kick(self, kick: FloorKick) -> bool:
        self._model.floor = kick
        return True


class SoftContacts:
    """The soft contact model on ``machine`` (:class:`~perga.contact.protocol.ContactModel`):
    ``granules`` the kernel's arrays, ``polygons`` the hammers (and a drawn wall) as contact
    polygons, ``log`` the impact log (None unless ``record_impacts``); energy is always
    measured (its terms cost nothing per step)."""

    def __init__(
        self, machine: Machine, *, record_impacts: bool = True, track_energy: bool = True
    ) -> None:
        spec = machine.spec
        self.machine = machine
        self.granule_dt = spec.granule_dt
        self.substeps = spec.contact_model.substeps
        self._machine_dt = spec.machine_dt
        self.polygons = MachinePolygons(machine)
        self._hammer_rows = machine.hammer_rows
        self.chunks = kernel_chunks(spec.contact_model.threads, len(spec.granules))
        """Chunks of the kernel's pair forces (:mod:`perga.contact.soft.threads`: from the case
        and the granules present at the start; the results depend on them)."""
        self._cores = CoreMonitor() if self.chunks > 1 else None
        """The free cores, looked at every ``RECHECK`` s while there are chunks to share."""
        self._next_look = monotonic() + RECHECK
        threads = kernel_threads(self.chunks, self._cores.free()) if self._cores else 1
        self.threads = threads
        """The most threads that have computed them at once (``granules.threads`` now: never
        more than the free cores; the results do not depend on them)."""
        self.granules = soft_granules(
            spec, self.polygons.polygons, self.polygons.materials, threads, self.chunks
        )
        self.materials = granule_table_materials(spec)
        """The granule-table rows' materials (those of granules present and fed, then a round
        chamber's)."""
        self.ids = np.arange(len(spec.granules), dtype=np.int64)
        self.log = (
            SoftImpactLog(
                self.granules,
                self.polygons.hammer_of,
                machine.hammer_state,
                self.present_ids,
                np.array([b.body_type == pymunk.Body.DYNAMIC for b in machine.hammer_bodies]),
                self._machine_dt,
            )
            if record_impacts
            else None
        )
        g = self.granules
        self._bonds = spec.has_bonds
        """Whether any granule, present or fed, is held (else no release to look for)."""
        self.releases: list[Release] = []
        self._reported = np.zeros(g.n, dtype=bool)
        self._released = -1  # the first look scans: bonds may have broken while building
        self._x0 = g.x.copy()
        self._granule_energy0 = self._granule_energies()
        self._kinetic0 = float(self._granule_energy0.sum())
        with numba_threads(self.granules.threads):
            self._elastic0 = g.contact_energy()
        self._gone = LedgerTerms()
        self._inflow = 0.0
        self._moment = 0.0
        self.kernel_share = (0, 0)
        """Processor cycles spent in kernel calls and in all of :meth:`machine_steps`' compiled
        steps so far (the kernel's share of them, for ``benchmarks/separator_speed.py``)."""
        self.floor: FloorKick | None = None
        """Floor friction's kick, once the effects' runner has handed it over
        (:meth:`_Kinematics.take_floor_kick`): the kernel call applies it first."""

    @property
    def impacts(self) -> list[Impact]:
        """Impacts completed so far (empty if recording is off)."""
        return [] if self.log is None else self.log.impacts

    @property
    def contact_episodes(self) -> list[Contact]:
        """Granule-hammer contacts ended so far (empty if recording is off)."""
        return [] if self.log is None else self.log.contacts

    def running(self) -> AbstractContextManager[None]:
        """numba's thread count held at the run's first (``granules.threads``) over a run
        (each kernel call then finds it set: setting and restoring it a step is paid only while
        the free cores have changed the count)."""
        return numba_threads(self.granules.threads)

    def present_ids(self) -> np.ndarray:
        """The ids of the granules present, in the kernel's row order."""
        return self.ids

    def kinematics(self) -> _Kinematics:
        """The granules' velocities and positions for the kicks: the kernel's arrays, SI."""
        return _Kinematics(self)

    def before_machine_step(self, time: float, machine: MachineState) -> None:
        """Pose the hammers from ``machine``, take the granule steps (floor friction first, if
        handed over, with the rotor's ω of ``machine``), load the hammer bodies (module doc)."""
        self.polygons.pose(self.granule_dt, machine)
        if self._cores is not None:
            self._follow_free_cores()
        floor = self.floor
        self.granules.step(
            self.substeps,
            floor=None if floor is None else (floor, machine.table[0, 5] * u.ANGULAR_VELOCITY),
            kept=None if self.log is None else self.log.kept(),
        )
        moment = self.polygons.apply_loads()
        self._moment = moment * self._machine_dt / ANGULAR_IMPULSE

    def machine_steps(self, limit: int, machine: CompiledMachine) -> int:
        """Take up to ``limit`` machine steps in one compiled call
        (:mod:`perga.contact.soft.machine_steps`), stopping after one in which the kernel
        counted a contact change the impact log must look at, or a release; returns how many
        (0 where the pair forces are threaded: then a step at a time)."""
        g = self.granules
        if self._cores is not None or g.threaded:
            return 0
        kept = None if self.log is None else self.log.kept()
        floor = None if self.floor is None else (self.floor, 0.0)  # ω: each step's, in the loop
        out = machine_steps(
            limit,
            (machine.raw, machine.before, machine.after),
            (machine.metered, machine.meter),
            self.polygons.pose_arguments(self.granule_dt),
            self.polygons.load_arguments(),
            g.call_arguments(self.substeps),
            opening_of(floor, kept),
            (g.coasting, g.coast_pacing),
            (self._machine_dt, ANGULAR_IMPULSE),
            (self.log is not None, self._bonds),
        )
        steps, rebuilds, lists, coasted, g.start, g.nbr, g.hist, cstart, cpoly, moment = out[:10]
        g.took(steps, self.substeps, rebuilds, lists, coasted, cstart, cpoly)
        self._moment = moment
        self.kernel_share = (self.kernel_share[0] + out[10], self.kernel_share[1] + out[11])
        return steps

    def _follow_free_cores(self) -> None:
        """Threads as the free cores allow, looked at every ``RECHECK`` wall seconds: a job
        started on a core meanwhile takes a thread away, one ended gives it back."""
        now = monotonic()
        if now < self._next_look:
            return
        self._next_look = now + RECHECK
        threads = kernel_threads(self.chunks, self._cores.free())
        self.granules.set_threads(threads)
        self.threads = max(self.threads, threads)

    def after_machine_step(self, time: float, machine: MachineState) -> float:
        """Open and close impacts (hammer angles from ``machine``), report released granules;
        returns the loads' angular impulse about the axis on the rotor-driven hammers over the
        step, internal units."""
        if self.log is not None:
            self.log.after(time, machine, self._hammer_rows)
        if not self._bonds:
            return self._moment
        g = self.granules
        released = int(g.counts[COUNT_RELEASES])
        if released == self._released:
            return self._moment
        self._released = released
        new = np.flatnonzero((g.released_step >= 0) & ~self._reported)
        for i in new:
            t = (int(g.released_step[i]) + 1) * self.granule_dt
            self.releases.append(Release(t, int(self.ids[i]), float(g.release_force[i])))
        self._reported[new] = True
        return self._moment

    def _granule_energies(self) -> FloatArray:
        g = self.granules
        return 0.5 * g.m * np.sum(g.v**2, axis=1) + 0.5 * g.inertia * g.w**2

    def energy_terms(self) -> LedgerTerms:
        """The granules' terms since the model was built, J (module doc), with what fed and
        removed granules brought and took."""
        g = self.granules
        energies = self._granule_energies()
        with numba_threads(self.granules.threads):
            elastic = g.contact_energy()
        present = LedgerTerms(
            kinetic=float(energies.sum()),
            kinetic_initial=self._kinetic0,
            moved=0.5 * float(np.abs(energies - self._granule_energy0).sum()),
            gravity_work=float(np.sum(g.m * ((g.x - self._x0) @ np.asarray(g.gravity)))),
            contact_dissipation=float(np.sum(g.dissipated)),
            elastic=elastic,
            elastic_initial=self._elastic0,
            inflow=self._inflow,
        )
        return present + self._gone

    def granule_state(self) -> GranuleState:
        """The granules now, SI (copies of the kernel's arrays)."""
        g = self.granules
        inertia = np.where(np.isfinite(g.inertia), g.inertia, 0.0)
        return GranuleState(
            g.x.copy(),
            g.v.copy(),
            g.w.copy(),
            self.ids.copy(),
            g.r.copy(),
            g.m.copy(),
            inertia,
            g.held.astype(bool),
        )

    def add_granules(self, granules: Sequence[GranuleSpec], ids: Sequence[int]) -> None:
        """Append granules numbered ``ids`` to the kernel's arrays (held ones with their bond)."""
        specs = list(granules)
        if not specs:
            return
        materials = self.materials
        g = self.granules
        g.add(
            np.array([s.position for s in specs], dtype=float),
            np.array([s.radius for s in specs], dtype=float),
            np.array([s.mass for s in specs], dtype=float),
            mat=np.array([materials.index(s.material) for s in specs], dtype=np.int32),
            v=np.array([s.velocity for s in specs], dtype=float),
            w=np.array([s.angular_velocity for s in specs], dtype=float),
            held=np.array([s.bond_force is not None for s in specs]),
            bond_force=np.array(
                [math.inf if s.bond_force is None else s.bond_force for s in specs]
            ),
            bond_energy=np.array([s.bond_energy for s in specs], dtype=float),
        )
        n = len(specs)
        self.ids = np.append(self.ids, np.asarray(ids, dtype=np.int64))
        self._reported = np.append(self._reported, np.zeros(n, dtype=bool))
        self._x0 = np.vstack([self._x0, g.x[-n:]])
        energies = self._granule_energies()[-n:]
        self._granule_energy0 = np.append(self._granule_energy0, energies)
        self._inflow += float(energies.sum())
        if self.log is not None:
            self.log.rows_changed(np.ones(g.n - n, dtype=bool), n)

    def remove_granules(self, ids: Sequence[int]) -> None:
        """Remove the granules numbered ``ids``, booking what they take (kinetic energy, the
        elastic energy of their contacts, gravity's work on them)."""
        rows = np.flatnonzero(np.isin(self.ids, np.asarray(ids, dtype=np.int64)))
        if rows.size == 0:
            return
        g = self.granules
        energies = self._granule_energies()
        keep = np.ones(g.n, dtype=bool)
        keep[rows] = False
        fall = (g.x[rows] - self._x0[rows]) @ np.asarray(g.gravity)
        gone = LedgerTerms(
            moved=0.5 * float(np.abs(energies[rows] - self._granule_energy0[rows]).sum()),
            gravity_work=float(np.sum(g.m[rows] * fall)),
            outflow=float(energies[rows].sum()),
        )
        with numba_threads(self.granules.threads):
            elastic = g.remove(rows)
        self._gone = self._gone + gone + LedgerTerms(outflow=elastic)
        for name in ("ids", "_reported", "_x0", "_granule_energy0"):
            setattr(self, name, getattr(self, name)[keep])
        if self.log is not None:
            self.log.rows_changed(keep, 0)

    def contact_counts(self) -> tuple[np.ndarray, FloatArray]:
        """Per granule, its contacts now and the largest of their overlaps, m."""
        with numba_threads(self.granules.threads):
            return self.granules.contact_counts()
