"""Whole machine steps of the soft model in one compiled call
(``perga.contact.soft.machine_steps``, taken by ``Simulation.advance``): the floats of as many
``Simulation.step`` calls, and offered only where nothing of the step needs Python."""

import re
from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.contact.soft.kernel import COUNT_CONTACT_CHANGES
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

from .marks import TWO_THREADS

CASES = Path(__file__).resolve().parents[3] / "cases"
SWEPT = ("granules.placement.inner_radius=0.09", "granules.placement.outer_radius=0.12")
"""The soft separator's granules put where the hammers sweep: impacts from the first steps."""

GRANULE_ARRAYS = ("x", "v", "w", "hist", "polygon_hist", "wall_hist", "dissipated", "counts")
GRANULE_COUNTS = ("steps", "time", "n_rebuilds", "n_candidate_lists", "coasted")


def _twins(case: Path, *overrides: str, **options) -> tuple[Simulation, Simulation]:
    spec = compile_case(load_case(case, overrides=["solver.threads=1", *overrides]))
    return Simulation(spec, **options), Simulation(spec, **options)


def _one_by_one(sim: Simulation, duration: float) -> None:
    with sim.running():
        for _ in range(round(duration / sim.dt)):
            sim.step()


def _assert_same(whole: Simulation, single: Simulation) -> None:
    """Every state and record the two simulations hold, the same floats."""
    g, h = whole.contacts.granules, single.contacts.granules
    for name in GRANULE_ARRAYS:
        np.testing.assert_array_equal(getattr(g, name), getattr(h, name), err_msg=name)
    assert [getattr(g, n) for n in GRANULE_COUNTS] == [getattr(h, n) for n in GRANULE_COUNTS]
    np.testing.assert_array_equal(g.coast_pacing, h.coast_pacing)
    np.testing.assert_array_equal(whole.machine.state().table, single.machine.state().table)
    assert whole.steps == single.steps
    assert [repr(i) for i in whole.impacts] == [repr(i) for i in single.impacts]
    assert [repr(r) for r in whole.contacts.releases] == [repr(r) for r in single.contacts.releases]
    for a, b in zip(whole.machine.effects, single.machine.effects, strict=True):
        assert (a.removed, a.supplied) == (b.removed, b.supplied), a.name
    if whole.meter is not None:
        assert whole.energy() == single.energy()


def _batches(sim: Simulation, duration: float, limit: int) -> list[tuple[int, bool]]:
    """Advance ``sim`` by ``duration`` in calls of at most ``limit`` steps; each call's steps
    and whether the kernel counted a contact change in it."""
    counts = sim.contacts.granules.counts
    end = sim.steps + round(duration / sim.dt)
    out = []
    with sim.running():
        while sim.steps < end:
            changes = counts[COUNT_CONTACT_CHANGES]
            n = sim.advance(min(limit, end - sim.steps))
            out.append((n, bool(counts[COUNT_CONTACT_CHANGES] != changes)))
    return out


@pytest.mark.parametrize(
    "overrides",
    [
        (),
        ("effects.floor_friction.floor='stationary'",),
        ("hammers.swing_limit=0.3",),
    ],
    ids=["corotating floor, hinge friction", "stationary floor", "swing stops"],
)
def test_whole_steps_give_the_floats_of_steps_one_by_one(overrides) -> None:
    """0.02 s of the soft separator with its granules where the hammers sweep (hundreds of
    impacts), in compiled whole steps and one step at a time: granules, contacts, hammers,
    impact records, effects' energies and the ledger, the same floats; the compiled steps were
    taken (batches of many steps, each ending at a contact change or its limit) after the first
    step, which is pymunk's ``Space.step`` (it checks the bodies added to the space)."""
    whole, single = _twins(CASES / "soft-separator.toml", *SWEPT, *overrides)
    batches = _batches(whole, 0.02, 400)
    _one_by_one(single, 0.02)
    _assert_same(whole, single)
    assert len(whole.impacts) > 100
    assert sum(n for n, _ in batches if n > 1) > whole.steps / 2
    assert batches[0][0] == 1
    assert all(changed or n == 400 for n, changed in batches[1:-1])


def test_whole_steps_keep_what_calls_hand_on() -> None:
    """What one kernel call hands the next, set on both twins after their first step: a pause
    in the search for coasting granules (``granules.pace_coasting``), counted down and taken
    up, and a rebuild of the neighbour list asked for, made by the first call alone."""
    whole, single = _twins(CASES / "soft-separator.toml", *SWEPT)
    for sim in (whole, single):
        sim.step()
        sim.contacts.granules.coast_pacing[:] = (3, 8)
        sim.contacts.granules._rebuild = True
    rebuilds = whole.contacts.granules.n_rebuilds
    _batches(whole, 0.005, 400)
    _one_by_one(single, 0.005)
    _assert_same(whole, single)
    assert whole.contacts.granules.coasted > 0
    assert whole.contacts.granules.n_rebuilds > rebuilds


@pytest.mark.parametrize(
    "options",
    [{"track_energy": False}, {"record_impacts": False}],
    ids=["no meter", "no impact log"],
)
def test_whole_steps_without_a_meter_or_a_log(options) -> None:
    """Without the energy meter the compiled steps book nothing for it; without the impact log
    they do not stop at contact changes: still the floats of steps one by one."""
    whole, single = _twins(CASES / "soft-separator.toml", *SWEPT, **options)
    batches = _batches(whole, 0.01, 400)
    _one_by_one(single, 0.01)
    _assert_same(whole, single)
    if "record_impacts" in options:
        assert all(n == 400 for n, _ in batches[1:-1])


def _combs_held_still(tmp_path: Path, action: str) -> Path:
    """The bee-bread separator without its feed and outlet: the comb piece at t = 0 only,
    held in its cells, struck by the hammers; damage marks or removes broken granules."""
    text = (CASES / "bee-bread-separator.toml").read_text(encoding="utf-8")
    sections = re.split(r"(?m)^(?=\[)", text)
    text = "".join(s for s in sections if not s.startswith(("[feed]", "[outlet]")))
    text = text.replace('action = "mark"', f'action = "{action}"')
    text = text.replace('path = "../geometry/', f'path = "{CASES.parent}/geometry/')
    case = tmp_path / "comb.toml"
    case.write_text(text, encoding="utf-8")
    return case


@pytest.mark.parametrize("action", ["mark", "remove"])
def test_whole_steps_release_granules_and_break_them_as_steps_do(tmp_path, action) -> None:
    """Granules pulled out of their comb cells and the impacts' damage: the compiled steps stop
    after a release and the process runs on the impacts, as one step at a time; broken
    granules removed between compiled steps (the next call rebuilds the neighbour list)."""
    whole, single = _twins(_combs_held_still(tmp_path, action))
    assert whole.feed is None and whole.outlet is None and whole.damage is not None
    batches = _batches(whole, 0.03, 1000)
    _one_by_one(single, 0.03)
    _assert_same(whole, single)
    assert len(whole.contacts.releases) > 0 and len(whole.impacts) > 0
    assert whole.damage.survival == single.damage.survival
    assert (whole.removed_broken > 0) == (action == "remove")
    assert sum(n for n, _ in batches if n > 1) > whole.steps / 2


@pytest.mark.parametrize(
    ("case", "overrides"),
    [
        ("soft-separator.toml", ("effects.air_drag.drag_coefficient=0.9",)),
        ("bee-bread-separator.toml", ()),
        pytest.param("soft-separator.toml", ("solver.threads=2",), marks=TWO_THREADS),
        ("separator.toml", ()),
    ],
    ids=["air drag", "feed and outlet", "threads", "rigid"],
)
def test_steps_that_need_python_are_taken_one_at_a_time(case, overrides) -> None:
    """Where a step needs Python (the runner's kicks, the process's feed and outlet, pair forces
    on threads, the rigid model's collision handlers), advance takes one step a call."""
    spec = compile_case(load_case(CASES / case, overrides=list(overrides)))
    sim = Simulation(spec)
    with sim.running():
        assert [sim.advance(50) for _ in range(5)] == [1] * 5
