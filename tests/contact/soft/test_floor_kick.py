"""Floor friction taken over by the soft kernel (``perga.machine.effects.FloorKick``): the kernel
call applies the kick and keeps the impact log's start state itself, with the same floats as
the effects' runner before the call did."""

from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.contact.soft.model import _Kinematics
from perga.engine.simulation import Simulation
from perga.machine.effects import AirDrag, FloorFriction
from perga.model.compile import compile_case

CASE = Path(__file__).resolve().parents[3] / "cases/soft-separator.toml"


def _twins(monkeypatch, *overrides: str) -> tuple[Simulation, Simulation]:
    """The soft separator built twice: as it is, and with the runner keeping every kick."""
    spec = compile_case(load_case(CASE, overrides=["solver.threads=1", *overrides]))
    taken = Simulation(spec)
    with monkeypatch.context() as patch:
        patch.setattr(_Kinematics, "take_floor_kick", lambda self, kick: False)
        kept = Simulation(spec)
    return taken, kept


def _effect(sim: Simulation, kind: type) -> FloorFriction | AirDrag:
    (effect,) = [e for e in sim.machine.effects if isinstance(e, kind)]
    return effect


@pytest.mark.parametrize("floor", ["corotating", "stationary"])
def test_the_kernel_kicks_as_the_runner_did(monkeypatch, floor):
    """0.05 s of the soft separator with its granules put where the hammers sweep: positions,
    velocities, spins, the friction's removed and supplied energy and every impact record are
    the same floats, and each impact's velocity before is the granule's after the kick of the
    step it began in (the runner's simulation, recorded at each kernel call)."""
    taken, kept = _twins(
        monkeypatch, f"effects.floor_friction.floor={floor!r}",
        "granules.placement.inner_radius=0.09", "granules.placement.outer_radius=0.12",
    )  # fmt: skip
    assert taken.kicks is None and taken.contacts.floor is not None
    assert kept.kicks is not None and kept.contacts.floor is None
    starts = []  # the velocities at each kernel call's start in the runner's simulation
    step = kept.contacts.granules.step

    def recording(*args, **kwargs):
        starts.append(kept.contacts.granules.v.copy())
        step(*args, **kwargs)

    monkeypatch.setattr(kept.contacts.granules, "step", recording)
    taken.run(0.05)
    kept.run(0.05)
    a, b = taken.frame(contacts=False).granules, kept.frame(contacts=False).granules
    for name in ("positions", "velocities", "angular_velocities"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    friction, reference = _effect(taken, FloorFriction), _effect(kept, FloorFriction)
    assert friction.removed > 0.0
    assert (friction.removed, friction.supplied) == (reference.removed, reference.supplied)
    assert (friction.supplied != 0.0) == (floor == "corotating")
    assert [repr(i) for i in taken.impacts] == [repr(i) for i in kept.impacts]
    assert len(taken.impacts) > 100
    for impact in taken.impacts:  # the state the kernel kept: after the kick, before the steps
        began = round(impact.time / taken.dt) - 1  # time: the end of the step it began in
        assert impact.granule_velocity_before == tuple(starts[began][impact.granule])


def test_a_kick_after_the_floors_stays_with_the_runner(monkeypatch):
    """With air drag, which comes after floor friction, nothing is handed over: the kernel
    would kick after the drag instead of before it."""
    taken, _ = _twins(monkeypatch, "effects.air_drag.drag_coefficient=0.9")
    assert taken.contacts.floor is None
    assert [type(k) for k in taken.kicks.kicks] == [FloorFriction, AirDrag]
