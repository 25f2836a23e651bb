"""Soft granules beside Pymunk's rotor and hammers: :class:`SoftSimulation`.

Step order of :meth:`SoftSimulation.step` (one Pymunk step of ``machine_dt`` = k granule steps):

1. The kicks the spec lists (floor friction, air drag: :mod:`perga.engine.effects`) change the
   granules' velocities over the Pymunk step, as in the rigid engine.
2. Each hammer is posed one granule step ahead along its current motion
   (:mod:`perga.contact.soft.machine` explains why).
3. The kernel takes k granule steps in one compiled call (:mod:`perga.contact.soft`): pair, wall and
   hammer contacts, kick-drift; hammers move rigidly with their current velocities during the
   call and the mean load on each is returned.
4. The mean loads become the hammer bodies' force and torque; Chipmunk steps rotor and hammers
   (joints, hinge friction, drive) by ``machine_dt``; the energy meter balances the rotor's
   angular momentum with those loads' moment about the axis.
5. The impact log opens and closes granule-hammer impacts (:mod:`perga.contact.soft.impacts`).

Energy: the ledger adds to the Pymunk bodies' terms the granules' kinetic energy, the elastic
energy stored in their contacts, the work of in-plane gravity on them, and the energy the
contacts dissipated, measured by the kernel from the contact law itself (dashpots, Coulomb
slip, rolling resistance), not as a balance: the closure stays a real check.
"""

from __future__ import annotations

import numpy as np

from perga.contact.soft.build import soft_granules
from perga.contact.soft.impacts import SoftImpactLog
from perga.contact.soft.machine import MachinePolygons
from perga.engine import units as u
from perga.engine.effects import Kick, run_kicks
from perga.engine.energy import EnergyLedger, LedgerTerms
from perga.engine.machine import Scene, build_scene
from perga.engine.simulation import FloatArray, Impact, Simulation, hammer_state
from perga.model.spec import SceneSpec


class SoftSimulation(Simulation):
    """A scene with soft granules; the accessors of :class:`Simulation` (``dt`` is the Pymunk
    step, ``granule_dt`` the granules')."""

    def __init__(
        self, scene: Scene, *, record_impacts: bool = True, track_energy: bool = True
    ) -> None:
        spec = scene.spec
        if spec.soft is None:
            raise ValueError("SoftSimulation needs a scene with soft contacts (spec.soft)")
        super().__init__(scene, record_impacts=False, track_energy=track_energy)
        self.dt = spec.machine_dt
        self._dt_internal = u.to_internal(self.dt, u.TIME)
        self.granule_dt = spec.dt
        self.substeps = spec.soft.substeps
        self.machine = MachinePolygons(scene)
        self.granules = soft_granules(spec, self.machine.polygons, self.machine.materials)
        self._kicks = [e for e in scene.effects if isinstance(e, Kick)]
        self._kick_positions = any(k.needs_positions for k in self._kicks)
        self.log = (
            SoftImpactLog(self.granules, self.machine.hammer_of, lambda k: hammer_state(scene, k))
            if record_impacts
            else None
        )
        g = self.granules
        self._x0 = g.x.copy()
        self._granule_energy0 = self._granule_energies()
        self._elastic0 = g.contact_energy()

    @classmethod
    def from_spec(cls, spec: SceneSpec, **options: bool) -> SoftSimulation:
        """Build the scene (rotor and hammers in Pymunk) and its soft granules."""
        return cls(build_scene(spec), **options)

    @property
    def impacts(self) -> list[Impact]:
        """Impacts completed so far (empty if recording is off)."""
        return [] if self.log is None else self.log.impacts

    def step(self) -> None:
        """Advance by one Pymunk step (``substeps`` granule steps)."""
        g = self.granules
        if self._kicks:
            positions = g.x / u.LENGTH if self._kick_positions else None
            v = run_kicks(self._kicks, g.v / u.VELOCITY, positions, self._dt_internal)
            g.v[:] = v * u.VELOCITY
        self.machine.pose(self.granule_dt)
        if self.log is not None:
            self.log.before()
        g.step(self.substeps)
        moment = self.machine.apply_loads()
        if self.meter is None:
            self.scene.space.step(self._dt_internal)
        else:
            self.meter.before_step()
            self.meter.add_moment(moment * self.dt / (u.FORCE * u.LENGTH * u.TIME))
            self.scene.space.step(self._dt_internal)
            self.meter.after_step(self._dt_internal)
        self.steps += 1
        if self.log is not None:
            self.log.after(self.time, np.array([b.angle for b in self.scene.hammer_bodies]))

    def _granule_energies(self) -> FloatArray:
        g = self.granules
        return 0.5 * g.m * np.sum(g.v**2, axis=1) + 0.5 * g.inertia * g.w**2

    def energy(self) -> EnergyLedger:
        """The ledger since the simulation was created, J (see the module doc)."""
        if self.meter is None:
            raise RuntimeError("energy() needs SoftSimulation(..., track_energy=True)")
        hammers = self.meter.terms()
        g = self.granules
        energies = self._granule_energies()
        lost = g.dissipated
        return LedgerTerms(
            kinetic=hammers.kinetic + float(energies.sum()),
            kinetic_initial=hammers.kinetic_initial + float(self._granule_energy0.sum()),
            moved=hammers.moved + 0.5 * float(np.abs(energies - self._granule_energy0).sum()),
            drive_work=hammers.drive_work,
            gravity_work=hammers.gravity_work
            + float(np.sum(g.m * ((g.x - self._x0) @ np.asarray(g.gravity)))),
            contact_dissipation=hammers.contact_dissipation + float(np.sum(lost)),
            friction=hammers.friction,
            drag=hammers.drag,
            elastic=g.contact_energy(),
            elastic_initial=self._elastic0,
        ).close()

    # --- state in SI (copies of the kernel's arrays) -------------------------------------------

    def granule_positions(self) -> FloatArray:
        """Granule centres, (n, 2) array, m."""
        return self.granules.x.copy()

    def granule_velocities(self) -> FloatArray:
        """Granule centre velocities, (n, 2) array, m/s."""
        return self.granules.v.copy()

    def granule_angular_velocities(self) -> FloatArray:
        """Granule angular velocities, (n,) array, rad/s."""
        return self.granules.w.copy()
