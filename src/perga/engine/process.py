"""The separator as a process, run between machine steps by the simulation
(:mod:`perga.engine.simulation`): granules fed into the chamber, granules leaving through the
outlet, granules broken by impacts. Each part is built only when the system has it
(:class:`perga.model.process.ProcessSpec`) and costs nothing otherwise.

* :class:`Feed`: the items (granules or comb pieces) due by time t are ⌊rate·(t − start)⌋ + 1
  from ``start`` on, at most ``total``, none after ``stop``. Each is put at a random place of
  the region (up to ``ATTEMPTS`` tries) where none of its granules overlaps another granule (a
  k-d tree), a hammer as posed now, or the wall; an item that finds no place waits ``RETRY``
  before the next try, and the time items waited is kept (``waited``).
* :class:`Outlet`: free granules that reach the outlet are taken out, each a
  :class:`~perga.model.records.Departure`.
* :class:`Damage`: each granule-hammer impact of normal approach speed v_n has the
  mass-specific energy W = ½v_n² (J/kg) and breaks the granule of size x (its diameter) with
  probability P = 1 − exp(−f_mat·x·(W − W_min)) for W > W_min; the granule's expected
  survival is the product of 1 − P over its impacts, exp(−f_mat·x·Σ(W_i − W_min)⁺), so that
  its breakage probability so far, 1 − survival, is for k equal impacts Vogel & Peukert's
  (2003, Powder Technol. 129, 101) S = 1 − exp(−f_mat·x·k·(W − W_min)); the impacts above
  W_min are counted (k). Whether it broke is drawn from P (seeded); broken granules are
  marked, or removed.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from perga.geometry.clearance import Obstacles, clear_of
from perga.model.process import DamageSpec, FeedSpec, OutletSpec
from perga.model.records import Departure, Impact
from perga.model.system import GranuleSpec

if TYPE_CHECKING:
    from perga.engine.simulation import Simulation

ATTEMPTS = 50
"""Random places tried for one item in one step."""

RETRY = 1e-3
"""Simulated time after an item found no place before the feed tries again, s (a blocked
region would otherwise cost ``ATTEMPTS`` tries every step)."""


class Feed:
    """Inserts the items a :class:`~perga.model.process.FeedSpec` asks for (module doc)."""

    def __init__(self, spec: FeedSpec) -> None:
        self.spec = spec
        self.rng = np.random.default_rng(spec.seed)
        self.items = 0
        """Items put in so far."""
        self.waited = 0.0
        """Simulated time items spent waiting for a free place, s (summed over the items)."""
        self._piece = np.asarray(spec.piece, dtype=float).reshape(-1, 2)
        self._next_try = -math.inf

    def due(self, time: float) -> int:
        """Items due by ``time`` (s), in all."""
        s = self.spec
        if time < s.start:
            return 0
        n = math.floor(s.rate * (min(time, s.stop) - s.start) + 1e-9) + 1
        return n if s.total is None else min(n, s.total)

    def run(self, sim: Simulation, time: float) -> None:
        """Put in what is due and fits."""
        waiting = self.due(time) - self.items
        if waiting <= 0:
            return
        if time < self._next_try:
            self.waited += waiting * sim.dt
            return
        obstacles = sim.obstacles()
        state = sim.contacts.granule_state()
        others, other_radii = state.positions, state.radii
        specs: list[GranuleSpec] = []
        for item in range(waiting):
            placed = self._place(obstacles, others, other_radii)
            if placed is None:
                self.waited += (waiting - item) * sim.dt
                self._next_try = time + RETRY
                break
            positions, radii = placed
            others = np.vstack([others, positions])
            other_radii = np.append(other_radii, radii)
            specs += self._granules(positions, radii)
            self.items += 1
        if specs:
            sim.add_granules(specs, time)

    def _place(
        self, obstacles: Obstacles, others: np.ndarray, other_radii: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray] | None:
        (cx, cy), (w, h), angle = self.spec.region
        c, s = math.cos(angle), math.sin(angle)
        radii = self.spec.sizes.draw(self.rng, len(self._piece))
        for _ in range(ATTEMPTS):
            u, v = self.rng.uniform(-0.5, 0.5, 2) * (w, h)
            centre = np.array([cx + c * u - s * v, cy + s * u + c * v])
            positions = centre + self._piece
            if (
                obstacles.clear(positions, radii).all()
                and clear_of(positions, radii, others, other_radii).all()
            ):
                return positions, radii
        return None

    def _granules(self, positions: np.ndarray, radii: np.ndarray) -> list[GranuleSpec]:
        s = self.spec
        masses = s.mass_of(radii)
        return [
            GranuleSpec(
                position=(float(p[0]), float(p[1])),
                velocity=s.velocity,
                radius=float(r),
                mass=float(m),
                material=s.material,
                rolls=s.rolls,
                bond_force=s.bond_force,
                bond_energy=s.bond_energy,
            )
            for p, r, m in zip(positions, radii, masses, strict=True)
        ]


class Outlet:
    """Takes out the free granules that reach the outlet (module doc)."""

    def __init__(self, spec: OutletSpec) -> None:
        self.spec = spec
        self.departures: list[Departure] = []

    def run(self, sim: Simulation, time: float) -> None:
        """Record and remove the granules at the outlet."""
        state = sim.contacts.granule_state()
        leaving = np.flatnonzero(self.spec.leaving(state.positions, state.radii) & ~state.held)
        if leaving.size == 0:
            return
        speeds = np.hypot(state.velocities[:, 0], state.velocities[:, 1])
        for i in leaving:
            id_ = int(state.ids[i])
            self.departures.append(
                Departure(
                    time=time,
                    granule=id_,
                    radius=float(state.radii[i]),
                    mass=float(state.masses[i]),
                    speed=float(speeds[i]),
                    impacts=sim.impact_counts.get(id_, 0),
                    survival=sim.survival_of(id_),
                    broken=sim.broken_of(id_),
                    residence_time=time - sim.entered.get(id_, 0.0),
                )
            )
        sim.remove_granules(state.ids[leaving])


class Damage:
    """Breakage of granules by their impacts (module doc)."""

    def __init__(self, spec: DamageSpec) -> None:
        self.spec = spec
        self.rng = np.random.default_rng(spec.seed)
        self.survival: dict[int, float] = {}
        """Expected survival of each granule that has been struck, by id."""
        self.counted: dict[int, int] = {}
        """Impacts above W_min of each granule, by id."""
        self.broken: set[int] = set()
        self._pending: list[int] = []

    def annotate(self, impact: Impact, size: float) -> Impact:
        """The impact with its breakage probability and the granule's survival after it
        (``size``: the granule's diameter, m); draws whether it broke."""
        s = self.spec
        w = impact.specific_energy
        excess = max(w - s.w_min, 0.0)
        probability = 1.0 - math.exp(-s.f_mat * size * excess)
        id_ = impact.granule
        survival = self.survival.get(id_, 1.0) * (1.0 - probability)
        self.survival[id_] = survival
        if excess > 0:
            self.counted[id_] = self.counted.get(id_, 0) + 1
        if id_ not in self.broken and self.rng.uniform() < probability:
            self.broken.add(id_)
            if s.action == "remove":
                self._pending.append(id_)
        return replace(impact, breakage_probability=probability, survival=survival)

    def of(self, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For granules ``ids``: expected survival (-), broken (drawn), impacts above W_min."""
        survival = np.array([self.survival.get(int(i), 1.0) for i in ids], dtype=float)
        broken = np.array([int(i) in self.broken for i in ids], dtype=bool)
        counted = np.array([self.counted.get(int(i), 0) for i in ids], dtype=np.int64)
        return survival, broken, counted

    def run(self, sim: Simulation, time: float) -> int:
        """Remove the granules broken since the last call when the action is "remove";
        returns how many."""
        gone = self._pending
        self._pending = []
        if gone:
            sim.remove_granules(np.array(gone, dtype=np.int64))
        return len(gone)
