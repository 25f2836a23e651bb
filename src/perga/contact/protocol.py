"""What a contact model is to the simulation: the granules and every contact they make.

The one :class:`~perga.engine.simulation.Simulation` steps the machine (rotor, hammers, joints,
effects: Pymunk) and hands the granules to a contact model. A contact model is built on the
machine (:data:`perga.contact.MODELS` names them) and attaches to it whatever it needs (Pymunk
bodies and collision handlers, or arrays and a compiled kernel). Per machine step the
simulation calls, in this order (:mod:`perga.engine.simulation` has the whole step order):

1. the effects' kicks on :attr:`ContactModel.kinematics` (but one the model took over,
   :meth:`GranuleKinematics.take_floor_kick`);
2. :meth:`ContactModel.before_machine_step`, with the machine's state
   (:class:`~perga.machine.machine.MachineState`, internal units), which applies a kick it took
   over first;
3. Chipmunk's step of the space;
4. :meth:`ContactModel.after_machine_step`, with the state after it, which returns the angular
   impulse about the axis that the contacts put on the rotor-driven bodies (for the drive's
   work in the ledger).

A model may take several whole steps in one compiled call instead
(:meth:`ContactModel.machine_steps`), the same floats, where the step needs no Python.

Between steps the process (a feed, an outlet, damage) may add and remove granules; each has a
persistent number (its id), which impacts, releases and frames name.

Everything is in SI at this interface except the machine's states and that angular impulse,
which are in Chipmunk's internal units (:mod:`perga.machine.units`), as the machine and its
energy meter compute in them.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import AbstractContextManager
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from perga.machine.compiled import CompiledMachine
from perga.machine.effects import GranuleKinematics
from perga.machine.machine import MachineState
from perga.model.records import Contact, Impact, LedgerTerms, Release
from perga.model.system import GranuleSpec

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GranuleState:
    """One consistent read of the granules present, SI, one row each (fresh arrays).

    positions: centres, (n, 2), m; velocities: centre velocities, (n, 2), m/s;
    angular_velocities: (n,), rad/s; ids: persistent numbers (n,); radii (n,), m; masses (n,),
    kg; inertia (n,): moments about the centre, kg·m² (0 for a sliding point); held (n,): held
    in a comb cell.
    """

    positions: FloatArray
    velocities: FloatArray
    angular_velocities: FloatArray
    ids: NDArray[np.int64]
    radii: FloatArray
    masses: FloatArray
    inertia: FloatArray
    held: NDArray[np.bool_]


class ContactModel(Protocol):
    """Granules and their contacts (with each other, the hammers and the chamber wall).

    granule_dt: the granules' step, s (the machine step divided by the model's substeps);
    impacts: the granule-hammer impacts completed so far, in order; contact_episodes: the
    granule-hammer contacts ended so far, in order; threads: the most CPU threads its step has
    used at once.
    """

    granule_dt: float
    impacts: list[Impact]
    contact_episodes: list[Contact]
    threads: int

    def kinematics(self) -> GranuleKinematics:
        """The granules' velocities for the kicks (built on first use)."""
        ...

    def running(self) -> AbstractContextManager[None]:
        """A context held around a run of many steps: what the steps use that is costly to
        set up at each (soft: numba's thread count, which a step otherwise sets and restores)."""
        ...

    def before_machine_step(self, time: float, machine: MachineState) -> None:
        """Work before Chipmunk's step that ends at ``time`` (s); ``machine``: the rotor and
        hammers now."""
        ...

    def after_machine_step(self, time: float, machine: MachineState) -> float:
        """Work after Chipmunk's step that ended at ``time`` (s), ``machine`` the rotor and
        hammers now; returns the angular impulse about the rotor axis the contacts put on the
        rotor-driven bodies during the step, internal units (0 when energy is not tracked)."""
        ...

    def machine_steps(self, limit: int, machine: CompiledMachine) -> int:
        """Take up to ``limit`` whole machine steps in compiled code, each the floats of the
        four calls above with ``machine``'s compiled parts (Chipmunk's step, the state reads and
        the energy meter), but the work :meth:`after_machine_step` does for the last of them,
        which the simulation then calls; stop after a step that needs that work (a contact
        change to record, a release). Returns how many (0: none offered now)."""
        ...

    releases: list[Release]
    """Granules pulled out of their comb cells so far."""

    def add_granules(self, granules: Sequence[GranuleSpec], ids: Sequence[int]) -> None:
        """Add these granules, numbered ``ids``, between steps."""
        ...

    def remove_granules(self, ids: Sequence[int]) -> None:
        """Take the granules numbered ``ids`` out between steps, booking the energy they take
        (the ledger's outflow)."""
        ...

    def energy_terms(self) -> LedgerTerms:
        """The ledger terms the model measures (see :mod:`perga.machine.energy`), J."""
        ...

    def granule_state(self) -> GranuleState:
        """Positions, velocities and spins of the granules now."""
        ...

    def contact_counts(self) -> tuple[NDArray[np.int32], FloatArray] | None:
        """Per granule, its contacts now and the largest of their overlaps (m), where the model
        has overlaps; None where it has not (impulses)."""
        ...
