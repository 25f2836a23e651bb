"""Every recorded impact against the impact law with friction (perga.stats.impact_law): a
hand-built impact table with a known answer, and real rigid runs."""

import math
from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.cli import main
from perga.stats.impact_law import ISOLATED, check_impacts
from perga.stats.tables import Run, load_run

ROOT = Path(__file__).resolve().parents[2]
M, R, E, F = 2e-4, 0.002, 0.6, 0.4


def _hand_built(rows: list[dict[str, float]]) -> Run:
    """A welded plate on a rotor of prescribed speed (immovable: the law is the granule's
    own) and one granule of M, R, with the impact rows given."""
    case = load_case(
        ROOT / "cases" / "rebound-test.toml",
        overrides=[f"contacts[0].restitution={E}", f"contacts[0].friction={F}"],
    )
    columns = {k: np.array([r[k] for r in rows], dtype=float) for k in rows[0]}
    granules = {"id": np.array([0.0]), "radius": np.array([R]), "mass": np.array([M])}
    return Run(Path("hand-built"), case, {}, granules, {}, columns, {})


def _row(u_n: float, u_t: float, v_after: tuple[float, float], **extra: float) -> dict:
    """An impact on a face with n = +y (t = −x) of a granule at rest, spin 0."""
    return {
        "time": 0.01, "granule": 0, "hammer": 0, "x": 0.1, "y": 0.0, "nx": 0.0, "ny": 1.0,
        "normal_velocity_before": u_n, "tangential_velocity_before": u_t,
        "normal_velocity_after": -E * u_n, "tangential_velocity_after": 0.0,
        "vx_before": -u_t, "vy_before": u_n, "vx_after": v_after[0], "vy_after": v_after[1],
        "granule_spin_before": 0.0, "granule_spin_after": 0.0, "dissipated": 0.0,
        "granule_energy_gain": 0.0, "held": 0.0, "other_contacts": 0.0,
        "hammer_x_before": 0.1, "hammer_y_before": 0.0,
    } | extra  # fmt: skip


def test_a_hand_built_table_gives_the_known_answers() -> None:
    """u = (−2, 0.3) m/s on an immovable face sticks (|u_t| = 0.3 <= 3 f (1 + e)|u_n| = 3.84):
    J_n = (1 + e)·m·2, J_t = −0.3·m/3 (a disc's slip compliance 3/m), so the centre leaves
    at v_n' = 1.2 m/s and v_t' = 0.3 − 0.1 = 0.2 m/s along t (−x). A row recorded with that
    velocity agrees to rounding; one 2 % off along t errs by 2 %·0.2/|v'|; a held granule, one
    with another contact (two, one: both sides of isolation's limit), one not counted (−1) and a
    touch (u_n >= 0) get their regimes."""
    v_after = (-0.2, 1.2)  # t = −x
    rows = [
        _row(-2.0, 0.3, v_after),
        _row(-2.0, 0.3, (-0.204, 1.2)),
        _row(-2.0, 0.3, v_after, held=1.0),
        _row(-2.0, 0.3, v_after, other_contacts=2.0),
        _row(-2.0, 0.3, v_after, other_contacts=-1.0),
        _row(0.01, 0.3, v_after),
        _row(-2.0, 0.3, v_after, other_contacts=1.0),
    ]
    checks = check_impacts(_hand_built(rows))
    assert checks[0].regime == ISOLATED and checks[0].sticks
    assert checks[0].velocity_error < 1e-14
    assert checks[0].normal_restitution == pytest.approx((E, E), rel=1e-14)
    assert checks[1].velocity_error == pytest.approx(0.004 / math.hypot(0.2, 1.2), rel=1e-9)
    assert [c.regime for c in checks[2:]] == [
        "the granule is held in the comb",
        "2 other contacts during the impact",
        "its other contacts were not recorded",
        "no approach (u_n >= 0): a touch, not an impact",
        "1 other contact during the impact",
    ]
    assert math.isnan(checks[5].velocity_error)


def test_the_hinged_impacts_of_four_impacts_follow_the_law_with_friction(tmp_path: Path) -> None:
    """cases/four-impacts.toml: 13 impacts of hinged hammers on one granule, all isolated; the
    velocity after within 5e-4 of the law's (measured 3.2e-4, Chipmunk's ten iterations of the
    pin and the contact) and the spin within 1e-3 of the rim speed; the energy lost within
    1 %. Against the frictionless law impacts 2-4 missed by 30-36 %."""
    run = tmp_path / "run"
    assert main(["run", str(ROOT / "cases" / "four-impacts.toml"), "-o", str(run), "--quiet"]) == 0
    checks = check_impacts(load_run(run))
    assert len(checks) >= 4 and all(c.regime == ISOLATED for c in checks)
    assert max(c.velocity_error for c in checks) < 5e-4
    assert max(c.spin_error for c in checks) < 1e-3
    lost = np.array([c.dissipated for c in checks]).sum(axis=0)
    assert lost[0] == pytest.approx(lost[1], rel=0.01)


def test_a_free_hammer_is_predicted_about_its_recorded_centre(tmp_path: Path) -> None:
    """cases/two-body-impact.toml: a free hammer strikes a granule head-on; the law with the
    free body's compliance about the centre the log recorded gives the run's velocity after to
    rounding (1e-12: one impulse, no pin to iterate)."""
    run = tmp_path / "run"
    case = str(ROOT / "cases" / "two-body-impact.toml")
    assert main(["run", case, "-o", str(run), "--quiet"]) == 0
    (check,) = check_impacts(load_run(run))
    assert check.regime == ISOLATED and check.velocity_error < 1e-12
