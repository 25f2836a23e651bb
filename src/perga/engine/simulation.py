"""The one simulation: a machine (rotor, hammers, joints, effects in Pymunk) and a contact model
(the granules and their contacts, :mod:`perga.contact`), stepped together.

Step order of :meth:`Simulation.step` (one machine step dt, t_n -> t_{n+1}; dt =
``System.machine_dt``, the granules take ``contact_model.substeps`` steps of
``System.granule_dt`` inside it):

1. Kicks: only if the spec lists them, floor friction and air drag change all granules'
   velocities at once from (x_n, v_n) (:mod:`perga.machine.effects`): an operator split before
   everything else, so the contacts and the drift see the kicked velocities. A contact model
   that takes floor friction over (the soft one) applies it first thing in 2 instead.
2. The machine's state is read (:meth:`~perga.machine.machine.Machine.state`: rotor and hammer
   bodies, read raw from their structs), and handed to the contact model's work before the
   machine moves (:meth:`~perga.contact.protocol.ContactModel.before_machine_step`): rigid,
   nothing moves yet (the granules are bodies of the space: their velocities are read for the
   dissipation); soft, the kernel advances the granules over the step against the hammers
   posed ahead (kicked by each granule step's loads) and loads the hammer bodies with the mean
   contact force, moving them by their recoil within the step.
3. The energy meter keeps that state (the rotor-driven bodies' velocities).
4. Chipmunk's step of the space: positions and angles advance with the current velocities
   (the kinematic rotor turns by ω·dt), collision detection at the new positions (rigid
   contacts call their handlers: the impact recorder's start, the pair setters, the outline
   filter), gravity and the bodies' forces are added to the velocities, and the impulse solver
   runs ``iterations`` times over contacts and joints (``post_solve``: impacts completed).
5. The machine's state is read again and handed to the contact model's work after it
   (:meth:`~perga.contact.protocol.ContactModel.after_machine_step`): rigid, the arbiters'
   dissipation; soft, the impact log. It returns the contacts' angular impulse on the
   rotor-driven bodies, which the meter needs for the drive's work.
6. The meter balances the rotor-driven bodies' angular momentum and books the constraint
   effects' losses (hinge friction, swing stops) from the two states
   (:mod:`perga.machine.energy`).
7. The step counter is incremented; ``time`` is n·dt from the integer count (no drift).
8. The process, if the system has one (:mod:`perga.engine.process`): with damage the step's
   new impacts get their breakage (each carries its specific energy from its making);
   broken granules to be removed are removed, granules at the outlet leave, the feed puts in
   what is due.

Because positions move before velocities are updated (step 4), the state after a step is
(x_{n+1}, v_{n+1}) with v_{n+1} computed from the forces at x_{n+1}: symplectic Euler, first
order; in leapfrog terms the velocities are half a step ahead of the positions. Soft granules
and the hammers they load form one kick-drift scheme (docs/architecture.md).

:meth:`Simulation.advance` takes several steps at once in this order, compiled, where the
contact model offers it and nothing of the step needs Python (docs/architecture.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from contextlib import AbstractContextManager

import numpy as np
from numpy.typing import NDArray

from perga.contact import contact_model
from perga.contact.protocol import ContactModel
from perga.engine.process import Damage, Feed, Outlet
from perga.geometry.clearance import Obstacles
from perga.machine import units as u
from perga.machine.compiled import CompiledMachine, compiled_machine
from perga.machine.effects import KickRunner
from perga.machine.energy import EnergyMeter
from perga.machine.machine import Machine, build_machine
from perga.model.frame import Frame, GranuleFrame, frozen
from perga.model.records import EnergyLedger, Events, Impact
from perga.model.system import GranuleSpec, System

FloatArray = NDArray[np.float64]


class Simulation:
    """Steps the system ``spec`` at its machine step (module doc for the order).

    ``machine`` is the Pymunk side, ``contacts`` the contact model the spec names
    (:data:`perga.contact.MODELS`). record_impacts: keep an
    :class:`~perga.model.records.Impact` per granule-hammer impact; track_energy: measure the
    energy ledger from now on.
    """

    def __init__(
        self, spec: System, *, record_impacts: bool = True, track_energy: bool = True
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
        kicks = KickRunner(self.machine.effects, self.contacts.kinematics(), self.dt)
        self.kicks = kicks if kicks else None
        """The effects' kicks on the granules (None when the spec lists none, or the contact
        model took the only one over)."""
        self.meter = EnergyMeter(self.machine) if track_energy else None
        process = spec.process
        self.feed = Feed(process.feed) if process.feed else None
        self.outlet = Outlet(process.outlet) if process.outlet else None
        self.damage = Damage(process.damage) if process.damage else None
        self.impacts: list[Impact] = []
        """Every impact so far, with its specific energy (and breakage, with damage)."""
        self.impact_counts: dict[int, int] = {}
        """Granule-hammer impacts of each granule so far, by id."""
        self.entered: dict[int, float] = {}
        """When each granule was fed or released from its cell, s, by id (absent: t = 0)."""
        self.fed = len(spec.granules)
        """Granules put in so far, those at t = 0 included."""
        self.removed_broken = 0
        self._seen = 0
        self._releases_seen = 0
        self._next_id = len(spec.granules)
        self._material_names = tuple(sorted(spec.granule_materials))
        self._material_of = [self._material_names.index(g.material) for g in spec.granules]
        """Each granule's material (an index into the names), by id."""
        self._outlines = [np.asarray(h.outline, dtype=float) for h in spec.hammers]
        if self.feed is not None:
            self.feed.run(self, 0.0)

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.steps * self.dt

    @property
    def threads(self) -> int:
        """The most CPU threads the contact model's steps have used at once."""
        return self.contacts.threads

    def step(self) -> None:
        """Advance by one machine step dt."""
        end = (self.steps + 1) * self.dt
        if self.kicks is not None:
            self.kicks.run(self.dt)
        before = self.machine.state()
        self.contacts.before_machine_step(end, before)
        if self.meter is not None:
            self.meter.before_step(before)
        self.machine.space.step(self._dt_internal)
        after = self.machine.state()
        moment = self.contacts.after_machine_step(end, after)
        if self.meter is not None:
            self.meter.after_step(self._dt_internal, moment, after)
        self.steps += 1
        self._process(end)

    def advance(self, limit: int) -> int:
        """Advance by 1 to ``limit`` machine steps, the floats of as many :meth:`step` calls;
        returns how many. Where the contact model offers it and nothing of the step needs Python
        (no kicks but one it took over, no feed, no outlet), it takes them in one compiled call
        (:meth:`~perga.contact.protocol.ContactModel.machine_steps`), which stops after a step
        whose contacts changed; that step's work after Chipmunk's (the impact log) and the
        process then run here."""
        compiled = self._compiled() if limit > 1 else None
        n = 0 if compiled is None else self.contacts.machine_steps(limit, compiled)
        if n == 0:
            self.step()
            return 1
        self.steps += n
        end = self.steps * self.dt
        self.contacts.after_machine_step(end, self.machine.state())
        self._process(end)
        return n

    def _compiled(self) -> CompiledMachine | None:
        """The machine's part of steps for :meth:`advance`, or None where a step needs Python."""
        if self.kicks is not None or self.feed is not None or self.outlet is not None:
            return None
        return compiled_machine(self.machine, self.meter, self._dt_internal)

    def _process(self, time: float) -> None:
        """Step 8 of the order (module doc)."""
        impacts = self.contacts.impacts
        if len(impacts) > self._seen:
            new = impacts[self._seen :]
            self._seen += len(new)
            sizes = dict(zip(*self._ids_and_sizes(), strict=True)) if self.damage else {}
            for impact in new:
                if self.damage is not None:
                    impact = self.damage.annotate(impact, sizes.get(impact.granule, math.nan))
                self.impacts.append(impact)
                self.impact_counts[impact.granule] = self.impact_counts.get(impact.granule, 0) + 1
        releases = self.contacts.releases
        if len(releases) > self._releases_seen:
            for release in releases[self._releases_seen :]:
                self.entered[release.granule] = release.time
            self._releases_seen = len(releases)
        if self.damage is not None:
            self.removed_broken += self.damage.run(self, time)
        if self.outlet is not None:
            self.outlet.run(self, time)
        if self.feed is not None:
            self.feed.run(self, time)

    def _ids_and_sizes(self) -> tuple[NDArray[np.int64], FloatArray]:
        state = self.contacts.granule_state()
        return state.ids, 2.0 * state.radii

    # --- the process's access to the granules ----------------------------------------------

    def add_granules(self, granules: list[GranuleSpec], time: float) -> None:
        """Put ``granules`` in now (numbered on from the last id), entered at ``time`` (s)."""
        ids = list(range(self._next_id, self._next_id + len(granules)))
        self._next_id += len(granules)
        self.contacts.add_granules(granules, ids)
        self._material_of += [self._material_names.index(g.material) for g in granules]
        for id_ in ids:
            self.entered[id_] = time
        self.fed += len(granules)

    def remove_granules(self, ids: NDArray[np.int64]) -> None:
        """Take the granules numbered ``ids`` out."""
        self.contacts.remove_granules([int(i) for i in ids])

    def obstacles(self) -> Obstacles:
        """The hammers as posed now and the chamber: where a granule may not be put."""
        hammers = self.machine.frame(self.dt).posed(self._outlines)
        chamber = self.spec.chamber
        if chamber is None:
            return Obstacles(hammers)
        if chamber.outline is None:
            return Obstacles(hammers, container_radius=chamber.radius)
        return Obstacles(hammers, container=chamber.inner_outline())

    def survival_of(self, id_: int) -> float:
        """Granule ``id_``'s expected survival (1 without damage or impacts)."""
        return 1.0 if self.damage is None else self.damage.survival.get(id_, 1.0)

    def broken_of(self, id_: int) -> bool:
        """Whether granule ``id_`` broke (drawn; False without damage)."""
        return self.damage is not None and id_ in self.damage.broken

    def running(self) -> AbstractContextManager[None]:
        """A context to hold around many steps: what the steps use that is costly to set up at
        each (the contact model's, :meth:`~perga.contact.protocol.ContactModel.running`)."""
        return self.contacts.running()

    def advance_to(self, step: int, between: Callable[[], None] | None = None) -> None:
        """Advance to step ``step`` (>= the step now), the floats of as many :meth:`step` calls,
        calling ``between()`` after each :meth:`advance` short of it (a driver's safe point,
        e.g. for a stop signal); hold :meth:`running` around many calls."""
        if step < self.steps:
            raise ValueError(f"step {step} is before the simulation's step {self.steps}")
        while self.steps < step:
            self.advance(step - self.steps)
            if between is not None and self.steps < step:
                between()

    def run(self, duration: float) -> int:
        """Advance by ``duration`` (s), rounded to a whole number of steps; returns the count."""
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0 s (got {duration})")
        n = round(duration / self.dt)
        with self.running():
            self.advance_to(self.steps + n)
        return n

    def energy(self) -> EnergyLedger:
        """The energy ledger since the simulation was created (J; needs ``track_energy``)."""
        if self.meter is None:
            raise RuntimeError("energy() needs Simulation(..., track_energy=True)")
        granules = self.contacts.energy_terms()
        return (self.meter.terms() + granules).close(granules)

    def frame(self, *, contacts: bool = True) -> Frame:
        """The simulation now as a :class:`~perga.model.frame.Frame` (with the ledger when
        energy is tracked; with the granules' contact counts where the contact model has them,
        unless ``contacts`` is False)."""
        state = self.contacts.granule_state()
        counts = self.contacts.contact_counts() if contacts else None
        material_of = np.asarray(self._material_of, dtype=np.int32)
        n = len(state.ids)
        if self.damage is None:
            survival, broken, damaging = np.ones(n), np.zeros(n, bool), np.zeros(n, np.int64)
        else:
            survival, broken, damaging = self.damage.of(state.ids)
        granules = GranuleFrame(
            ids=frozen(state.ids),
            radii=frozen(state.radii),
            masses=frozen(state.masses),
            inertia=frozen(state.inertia),
            materials=frozen(material_of[state.ids]),
            material_names=self._material_names,
            positions=frozen(state.positions),
            velocities=frozen(state.velocities),
            angular_velocities=frozen(state.angular_velocities),
            held=frozen(state.held),
            survival=frozen(survival),
            broken=frozen(broken),
            damaging_impacts=frozen(damaging),
            contacts=None if counts is None else frozen(counts[0]),
            overlap_max=None if counts is None else frozen(counts[1]),
        )
        return Frame(
            time=self.time,
            step=self.steps,
            granules=granules,
            machine=self.machine.frame(self.dt),
            energy=None if self.meter is None else self.energy(),
            impacts=len(self.impacts),
            fed=self.fed,
            departed=0 if self.outlet is None else len(self.outlet.departures),
            broken=0 if self.damage is None else len(self.damage.broken),
            removed_broken=self.removed_broken,
            released=len(self.contacts.releases),
        )

    def events(self) -> Events:
        """The impacts, releases, departures and ended contacts so far (views of the growing
        lists)."""
        return Events(
            self.impacts,
            self.contacts.releases,
            () if self.outlet is None else self.outlet.departures,
            self.contacts.contact_episodes,
        )
