"""Named metrics (perga.stats.metrics) of rebound runs against the impulse law, and the reasons
a run cannot give one."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from perga.analytic.impact import oblique_impact
from perga.case import load_case
from perga.run import prepare_directory, run_case
from perga.stats import load_run
from perga.stats.metrics import METRICS, MetricUnavailableError, evaluate, parse_metric

ROOT = Path(__file__).resolve().parents[2]
REBOUND = ROOT / "cases" / "rebound-test.toml"


def _shot(tmp_path: Path, *overrides: str):
    case = load_case(REBOUND, overrides=list(overrides))
    directory = tmp_path / "run"
    prepare_directory(directory, overwrite=True)
    run_case(case, REBOUND, directory)
    return case, load_run(directory)


@pytest.mark.parametrize(("angle", "spin"), [(0.3, 0.0), (1.3, 0.0), (0.8, 400.0)])
def test_first_impact_metrics_equal_the_impulse_law(tmp_path: Path, angle: float, spin: float):
    """A disc shot at the face: e, β = −s'/s and the rebound angle against
    perga.analytic.impact.oblique_impact (slip s = v_t − ω r in the face's frame, t along
    the hammer's axis). One rigid impact is one impulse solve; what is left is Chipmunk's
    contact found up to one step deep (10 µm at 2e-6 s: 4e-3 of the radius), hence 2e-3 on β
    and the angle."""
    case, run = _shot(tmp_path, f"granules.placement.angle={angle}",
                      f"granules.placement.spin={spin}")  # fmt: skip
    g = case.granules
    v = g.placement.speed
    # the face's frame (n = +y, t = +x of the hammer, t × n = ẑ) is oblique_impact's: the
    # granule moves along −n and +t, its contact point slips at s = v_t + r·ω
    exact = oblique_impact(
        g.mass, g.radius, -v * math.cos(angle), v * math.sin(angle), 0.7, 0.3, omega_g=spin
    )
    assert evaluate(run, "impact_count") == 1
    assert evaluate(run, "first_impact_restitution") == pytest.approx(0.7, abs=1e-12)
    # impacts.csv's tangent is n turned +90° (−x here): v_t = −s, and β = −v_t'/v_t = −s'/s
    beta = evaluate(run, "first_impact_tangential_restitution_contact")
    assert beta == pytest.approx(-exact.slip_after / exact.slip_before, abs=2e-3)
    rebound = evaluate(run, "first_impact_rebound_angle_contact")
    normal_after = exact.normal_velocity
    assert rebound == pytest.approx(math.atan2(-exact.slip_after, normal_after), abs=2e-3)
    # the centre: its own tangential velocity, v sin θ before
    centre = evaluate(run, "first_impact_tangential_restitution_centre")
    assert centre == pytest.approx(-exact.tangential_velocity / (v * math.sin(angle)), abs=2e-3)
    rebound = evaluate(run, "first_impact_rebound_angle_centre")
    assert rebound == pytest.approx(math.atan2(-exact.tangential_velocity, normal_after), abs=2e-3)
    for name in ("first_impact_tangential_restitution_centre",
                 "first_impact_tangential_restitution_contact"):  # fmt: skip
        low, high = METRICS[name].bounds
        assert low <= evaluate(run, name) <= high or spin != 0.0
    assert abs(evaluate(run, "ledger_closure")) < 1e-9


def test_unavailable_metrics_say_why(tmp_path: Path) -> None:
    _, run = _shot(tmp_path, "granules.placement.angle=0.0")
    with pytest.raises(MetricUnavailableError, match="head-on impact has no tangential"):
        evaluate(run, "first_impact_tangential_restitution_contact")
    with pytest.raises(MetricUnavailableError, match="head-on"):
        evaluate(run, "first_impact_tangential_restitution_centre")
    with pytest.raises(MetricUnavailableError, match="made 1 impacts, not 2"):
        evaluate(run, "granule_speed_after_impact:2")
    with pytest.raises(MetricUnavailableError, match="outside the run"):
        evaluate(run, "radius_at:1.0")
    assert evaluate(run, "radius_at:0.0") == pytest.approx(
        math.hypot(*run.track(0)["x"][:1], *run.track(0)["y"][:1])
    )
    _, missed = _shot(tmp_path, "granules.placement.angle=1.4", "solver.duration=0.0005")
    with pytest.raises(MetricUnavailableError, match="made no granule-hammer impact"):
        evaluate(missed, "first_impact_restitution")


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("bogus", "unknown metric 'bogus'; metrics: impact_count"),
        ("first_impact_tangential_restitution", "is now two: first_impact_tangential_restitution_"),
        ("radius_at", "write it as radius_at:ARG"),
        ("impact_count:3", "write it as impact_count"),
        ("radius_at:soon", "'soon' is not a number"),
    ],
)
def test_metric_names_are_checked(name: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        parse_metric(name)


def test_every_metric_has_a_unit_and_a_description() -> None:
    assert all(m.unit and m.description for m in METRICS.values())
