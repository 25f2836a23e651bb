"""The machine's part of whole steps taken in compiled code by a contact model
(:meth:`~perga.contact.protocol.ContactModel.machine_steps`): Chipmunk's step with the state
reads, and the energy meter's step."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from perga.machine.energy import IDLE_METER, EnergyMeter
from perga.machine.machine import Machine

FloatArray = NDArray[np.float64]


class CompiledMachine(NamedTuple):
    """The machine's part of a step for compiled code that takes whole steps itself: ``raw``
    Chipmunk's step and the state read (:meth:`~perga.machine.machine.Machine.raw_step`),
    ``meter`` the energy meter's step (:meth:`~perga.machine.energy.EnergyMeter.compiled`;
    booked if ``metered``), ``before`` and ``after`` the machine-state tables the steps read
    into."""

    raw: tuple
    metered: bool
    meter: tuple
    before: FloatArray
    after: FloatArray


def compiled_machine(
    machine: Machine, meter: EnergyMeter | None, dt: float
) -> CompiledMachine | None:
    """The machine's part of compiled steps of ``dt`` (internal time units), metered by
    ``meter`` if any; None while pymunk's ``Space.step`` has work of its own. Take it afresh for
    each run of compiled steps: the addresses change with a checkpoint read back."""
    raw = machine.raw_step(dt)
    if raw is None:
        return None
    table = (len(raw[3]), 6)
    return CompiledMachine(
        raw,
        meter is not None,
        IDLE_METER if meter is None else meter.compiled(dt),
        np.empty(table),
        np.empty(table),
    )
