"""The simulation engine: the machine (rotor, hammers, joints, effects) in Pymunk
(:mod:`.machine`, :mod:`.effects`), the energy ledger (:mod:`.energy`), and the one
:class:`~perga.engine.simulation.Simulation` that steps the machine with a contact model
(:mod:`perga.contact`)."""

from perga.engine.machine import Machine, build_machine
from perga.engine.simulation import Simulation

__all__ = ["Machine", "Simulation", "build_machine"]
