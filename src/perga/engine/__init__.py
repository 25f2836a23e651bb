"""The one :class:`~perga.engine.simulation.Simulation`: the machine (:mod:`perga.machine`)
stepped with a contact model (:mod:`perga.contact`), and the process (:mod:`.process`: feed,
outlet, damage) between its steps."""

from perga.engine.simulation import Simulation

__all__ = ["Simulation"]
