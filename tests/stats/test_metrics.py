"""Named metrics (perga.stats.metrics) of rebound runs against the impulse law, and the reasons
a run cannot give one; rebound tests at any target (placement kind = "shot", target "hammer"
or "wall") and the shot metrics read from the trajectory as a rebound test measures it, with
the aim's refusals on both sides of their limits."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from perga.analytic.impact import oblique_impact
from perga.case import load_case
from perga.case.load import CaseError
from perga.model.placement import initial_state
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
    # rebound angles are forward-positive: on the side the slip (centre: velocity) had before
    forward = math.copysign(exact.slip_after, exact.slip_after * exact.slip_before)
    assert rebound == pytest.approx(math.atan2(forward, normal_after), abs=2e-3)
    # the centre: its own tangential velocity, v sin θ before
    centre = evaluate(run, "first_impact_tangential_restitution_centre")
    assert centre == pytest.approx(-exact.tangential_velocity / (v * math.sin(angle)), abs=2e-3)
    rebound = evaluate(run, "first_impact_rebound_angle_centre")
    assert rebound == pytest.approx(math.atan2(exact.tangential_velocity, normal_after), abs=2e-3)
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
    # the rebound test's hammer stands still: no share of its energy to speak of
    with pytest.raises(MetricUnavailableError, match="no impact with a moving hammer"):
        evaluate(run, "transfer_efficiency")
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


# --- shots at any target, read from the trajectory -------------------------------------------

POINTS = ("centre", "contact")


def test_a_hammer_shot_s_trajectory_gives_the_impact_log_s_rebound(tmp_path: Path) -> None:
    """Shot at the welded plate with spin: the trajectory's first and last frames give the
    impact log's e (1e-6), β and rebound angles at the centre and the contact point within
    2e-3, the bound both keep against the impulse law (tests/stats/test_metrics.py). Measured
    5e-4 apart on β at the centre: the log takes the contact's velocities at Chipmunk's contact
    point, half the overlap δ inside the rim, and the centre's as the rim's plus ω r, off by
    ω δ/2 (400 rad/s here); the trajectory reads the centre itself."""
    _, run = _shot(tmp_path, "granules.placement.angle=0.8", "granules.placement.spin=400.0")
    assert evaluate(run, "shot_restitution") == pytest.approx(
        evaluate(run, "first_impact_restitution"), abs=1e-6
    )
    for point in POINTS:
        for what in ("tangential_restitution", "rebound_angle"):
            assert evaluate(run, f"shot_{what}_{point}") == pytest.approx(
                evaluate(run, f"first_impact_{what}_{point}"), abs=2e-3
            ), (what, point)


@pytest.mark.parametrize("angle", [0.3, 1.3])
def test_a_wall_shot_rebounds_as_the_impulse_law(tmp_path: Path, angle: float) -> None:
    """Fired at the round chamber's flat edge on +x (steel, the same pair as the plate's):
    the trajectory's e, β and rebound angle at the centre against oblique_impact on an
    immovable face (2e-3: the contact found up to one step deep, as on the plate)."""
    case, run = _shot(
        tmp_path, "granules.placement.target=wall", f"granules.placement.angle={angle}"
    )
    g = case.granules
    v = g.placement.speed
    exact = oblique_impact(g.mass, g.radius, -v * math.cos(angle), v * math.sin(angle), 0.7, 0.3)
    assert evaluate(run, "impact_count") == 0  # a wall, not a hammer
    assert evaluate(run, "shot_restitution") == pytest.approx(0.7, abs=2e-3)
    beta = evaluate(run, "shot_tangential_restitution_centre")
    assert beta == pytest.approx(-exact.tangential_velocity / (v * math.sin(angle)), abs=2e-3)
    rebound = evaluate(run, "shot_rebound_angle_centre")
    # forward-positive, whichever way the wall's tangent runs
    assert rebound == pytest.approx(math.atan2(exact.tangential_velocity,
                                               exact.normal_velocity), abs=2e-3)  # fmt: skip


def test_an_angle_from_the_surface_is_its_complement_from_the_normal() -> None:
    by_normal = initial_state(load_case(REBOUND, overrides=["granules.placement.angle=0.4"]))
    by_surface = initial_state(
        load_case(
            REBOUND,
            overrides=[f"granules.placement.angle={math.pi / 2 - 0.4!r}",
                       "granules.placement.angle_from=surface"],
        )
    )  # fmt: skip
    for a, b in zip(by_normal, by_surface, strict=True):
        assert np.allclose(a, b, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (["granules.placement.angle_from=surface", "granules.placement.angle=0.0708"], None),
        (["granules.placement.angle_from=surface", "granules.placement.angle=0.07"],
         "an incidence of 1.501 rad from the normal: at most 1.5"),
        (["granules.placement.target=wall", "granules.placement.at=0.5"], None),
        (["granules.placement.at=0.5"], "at aims a shot at the wall"),
        (["granules.placement.target=wall", "granules.placement.along=0.05"],
         "a wall shot aims with at"),
    ],
)  # fmt: skip
def test_the_aim_is_refused_on_the_wrong_side_of_each_limit(overrides, message) -> None:
    if message is None:
        load_case(REBOUND, overrides=overrides)
        return
    with pytest.raises(CaseError, match=message):
        load_case(REBOUND, overrides=overrides)


def test_a_shot_that_has_not_rebounded_says_so(tmp_path: Path) -> None:
    _, run = _shot(tmp_path, "granules.placement.angle=1.4", "solver.duration=0.0005")
    with pytest.raises(MetricUnavailableError, match="has not rebounded by the run's end"):
        evaluate(run, "shot_restitution")


def test_the_ledger_s_metrics(tmp_path: Path) -> None:
    """dissipated_fraction and mean_speed_at_end read summary.json: the contacts' dissipation
    over the energy at the start and put in play, and the end speeds' mean (exactly)."""
    _, run = _shot(tmp_path, "granules.placement.angle=0.8")
    energy, speeds = run.summary["energy"], run.summary["speeds"]
    total = energy["kinetic_initial"] + energy["elastic_initial"] + energy["energy_in_play"]
    assert evaluate(run, "dissipated_fraction") == energy["contact_dissipation"] / total
    assert 0.0 < evaluate(run, "dissipated_fraction") < 1.0
    assert evaluate(run, "mean_speed_at_end") == speeds["mean"]
