"""Pairs that touch again: Chipmunk keeps a separated pair's accumulated impulses for
``collision_persistence`` steps and, should the pair touch again within them, starts its solve
from them without applying them (``cpArbiterUpdate`` copies them, ``cpArbiterApplyCachedImpulse``
skips a first contact). The contact could then pull by up to that impulse, friction's cap was
too high and the arbiter's total impulse, which the ledger and the impact log read, overstated
the impulse applied. perga forgets a separated pair at once (``perga.machine.machine``)."""

from pathlib import Path

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

CASES = Path(__file__).parents[3] / "cases"


def _closure(case: Path, duration: float, overrides: tuple[str, ...] = ()) -> float:
    sim = Simulation(compile_case(load_case(case, overrides=list(overrides))))
    with sim.running():
        sim.run(duration)
    assert sim.impacts, "the check needs impacts"
    return sim.energy().closure


def test_the_rigid_separators_ledger_closes_to_rounding() -> None:
    """The bundled rigid separator's first 0.16 s (111 impacts, granules meeting hammers, wall
    and each other again and again) closes to 2.8e-15 (rounding over 4,000 steps; nothing in the
    horizontal scene is first order); with the stale impulses it closed to +0.78 %."""
    assert abs(_closure(CASES / "separator.toml", 0.16)) < 1e-12


def test_a_comb_struck_with_rigid_impulses_closes(tmp_path: Path) -> None:
    """The bundled bee-bread separator with rigid impulses: hinged hammers strike granules held
    in the comb, which are set back in their cells after every step and so touch the hammer
    again and again. At 0.02 s (18 impacts) the ledger closes to +2.1e-5, gravity's kick split
    to first order in the step (module doc of ``perga.contact.rigid.dissipation``); the bound is
    ten times that. With the stale impulses it closed to +62 %."""
    text = (CASES / "bee-bread-separator.toml").read_text()
    start, end = text.index("[contact_model]"), text.index("[solver]")
    text = text[:start] + '[contact_model]\nkind = "rigid"\n\n' + text[end:]
    case = tmp_path / "rigid-comb.toml"
    case.write_text(text.replace("../geometry/", f"{CASES.parent / 'geometry'}/"))
    assert abs(_closure(case, 0.02)) < 2e-4
