"""An error in a collision listener stops the run: Chipmunk calls the listeners from C, which
would print the error and go on (a run that lost its impact log said "completed"); perga keeps
it and raises it after the step."""

from pathlib import Path

import pytest

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

CASES = Path(__file__).parents[3] / "cases"


class PlantedError(Exception):
    """The error planted in a listener."""


def test_an_error_in_a_listener_is_raised_after_its_step() -> None:
    sim = Simulation(compile_case(load_case(CASES / "four-impacts.toml")))
    calls = []

    def failing(arbiter, space, data):
        calls.append(sim.steps)
        raise PlantedError("planted")

    sim.contacts.bodies.listen("post_solve", failing, ("granule", "hammer"))
    with pytest.raises(PlantedError), sim.running():
        sim.run(0.5)
    assert calls, "the listener ran"
    # raised at the end of the step in which it was called: no step is counted after it
    assert sim.steps == calls[0]
