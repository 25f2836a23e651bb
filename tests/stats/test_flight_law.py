"""Every free flight between two hammer contacts against the flight over the floor
(perga.stats.flight_law): a hand-built table whose flights are the closed form's own (a
stationary floor: a straight line slowed at f g; errors are rounding), each regime on both
sides of its limit (a real run's flights: tests/stats/test_slide_law.py, the welded
separator)."""

from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.stats.flight_law import FREE, check_flights
from perga.stats.slide_law import SLIDE_STEPS
from perga.stats.tables import Run
from perga.stats.trajectory import free_flight

ROOT = Path(__file__).resolve().parents[2]
F, G, DT, T = 0.3, 9.80665, 4e-5, 0.01
R0, V0 = np.array([0.05, 0.02]), np.array([2.0, -1.0])


def _hand_built(pairs: list[tuple[dict, dict]]) -> Run:
    """The rebound test's scene over a stationary floor of friction F; each pair of contacts
    one granule's (its id the pair's index), with the next contact's impact row."""
    case = load_case(
        ROOT / "cases" / "rebound-test.toml",
        overrides=[
            "effects.floor_friction.floor=stationary",
            f"effects.floor_friction.friction={F}",
        ],
    )
    contacts = [row | {"granule": g} for g, pair in enumerate(pairs) for row in pair]
    columns = {k: np.array([r[k] for r in contacts], dtype=float) for k in contacts[0]}
    impacts = {
        "granule": columns["granule"], "hammer": columns["hammer"], "time": columns["start"],
        "vx_before": columns["vx_before"], "vy_before": columns["vy_before"],
    }  # fmt: skip
    n = len(pairs)
    granules = {"id": np.arange(n, dtype=float), "radius": np.full(n, 0.0025),
                "mass": np.full(n, 1.6e-4)}  # fmt: skip
    return Run(Path("hand-built"), case, {"time_step": {"machine": DT}}, granules, {}, impacts,
               {}, contacts=columns)  # fmt: skip


def _pair(gap: float = T, **first: float) -> tuple[dict, dict]:
    """A contact ending at R0 with V0, and the next beginning ``gap`` later where the closed
    form has the granule then (its velocity before the next impact the closed form's)."""
    (r1,) = free_flight([gap], R0, V0, F * G)
    speed = np.hypot(*V0) - F * G * gap
    v1 = V0 / np.hypot(*V0) * speed
    base = {"hammer": 0, "other_contacts": 0, "held": 0, "touches": 3,
            "x_start": 0.0, "y_start": 0.0, "vx_before": 0.0, "vy_before": 0.0}  # fmt: skip
    a = base | {"start": 0.1, "end": 0.1004, "x_end": R0[0], "y_end": R0[1], "vx_end": V0[0],
                "vy_end": V0[1]} | first  # fmt: skip
    b = base | {"start": 0.1004 + gap, "end": 0.1008 + gap, "x_start": r1[0], "y_start": r1[1],
                "vx_before": v1[0], "vy_before": v1[1], "x_end": 0.0, "y_end": 0.0,
                "vx_end": 0.0, "vy_end": 0.0}  # fmt: skip
    return a, b


def test_a_hand_built_table_gives_the_known_answers() -> None:
    """The closed form's own flight agrees to 1e-9 (the integrator's rtol 1e-10); one that
    touched another granule meanwhile (the touches one more at the next contact), one with
    another contact during the first, and a held granule get their regimes; a gap one step
    shorter than a contact time is no flight, one of a contact time is."""
    exact = _pair()
    touched = _pair()
    touched[1]["touches"] += 1
    pairs = [exact, touched, _pair(other_contacts=1), _pair(held=1),
             _pair(gap=(SLIDE_STEPS - 1) * DT), _pair(gap=SLIDE_STEPS * DT)]  # fmt: skip
    checks = check_flights(_hand_built(pairs))
    assert [c.granule for c in checks] == [0, 1, 2, 3, 5]
    assert checks[0].regime == FREE and checks[0].velocity_error < 1e-9
    assert checks[0].position_error < 1e-9
    assert [c.regime for c in checks[1:]] == [
        "it touched another granule or the wall",
        "it touched another granule or the wall",
        "the granule was held in the comb",
        FREE,
    ]


def test_soft_runs_are_refused_with_their_reason() -> None:
    run = _hand_built([_pair()])
    soft = Run(run.directory, run.case, run.summary, run.granules, {}, run.impacts, {},
               contacts=run.contacts | {"touches": np.full(2, -1.0)})  # fmt: skip
    with pytest.raises(ValueError, match="soft contacts do not count"):
        check_flights(soft)
