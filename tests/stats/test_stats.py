"""perga.stats against closed forms: synthetic tables, then a short real run.

Synthetic data are exact, so the tolerances there are round-off or the fit's conditioning
(1e-6); the real run is one rigid impulse solve, exact to round-off (docs/dev/validation.md), so
1e-9 catches any error in the bookkeeping.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from perga.analytic.impact import impact_efficiencies, normal_impact
from perga.case import load_case
from perga.run import prepare_directory, run_case
from perga.stats import Run, load_run
from perga.stats.energy import impact_speed_histogram, impact_stats, successive_energies
from perga.stats.sweeps import efficiency_point
from perga.stats.tables import read_table
from perga.stats.trajectory import amplitude_left, blade_frame, fit_exponential, free_flight

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_fit_exponential_recovers_rate_and_offset() -> None:
    t = np.linspace(0.0, 0.05, 200)
    y = 0.083 * np.exp(-42.55 * t) - 0.003
    fit = fit_exponential(t, y)
    assert fit.rate == pytest.approx(-42.55, rel=1e-6)
    assert fit.offset == pytest.approx(-0.003, rel=1e-6)
    assert fit.rms < 1e-9


def test_amplitude_left_of_an_exponential() -> None:
    t = np.linspace(0.0, 0.1, 2001)
    left = amplitude_left(t, np.exp(-30.0 * t), [0.02, 0.05])
    assert left == pytest.approx(np.exp(-30.0 * np.array([0.02, 0.05])), rel=1e-3)


def test_free_flight_stops_after_v2_over_2a() -> None:
    p = free_flight([0.0, 1.0, 10.0], (0.1, 0.0), (0.0, 3.0), 2.0)
    assert p[0] == pytest.approx([0.1, 0.0])
    assert p[1] == pytest.approx([0.1, 3.0 - 1.0])
    assert p[2] == pytest.approx([0.1, 9.0 / 4.0])  # stopped at v/a = 1.5 s


def test_blade_frame_of_a_point_turning_with_the_blade() -> None:
    omega, t = 30.0, np.linspace(0, 0.1, 11)
    theta = omega * t
    x, y = 0.05 * np.cos(theta), 0.05 * np.sin(theta)
    along, across, u = blade_frame(x, y, -omega * y, omega * x, theta, omega)
    assert along == pytest.approx(0.05) and across == pytest.approx(0.0, abs=1e-15)
    assert u == pytest.approx(0.0, abs=1e-12)


def _synthetic_run(tmp_path: Path, m: float, M: float, e: float, speeds: list[float]) -> Run:
    """A run with one granule struck by a free hammer of mass M at each speed (at rest before)."""
    case = load_case(CASES / "two-body-impact.toml")
    rows = [normal_impact(m, M, 0.0, v, e) for v in speeds]
    n = len(rows)
    impacts = {
        "time": np.arange(1.0, n + 1),
        "granule": np.zeros(n),
        "hammer": np.zeros(n),
        "normal_velocity_before": -np.array(speeds),
        "normal_velocity_after": np.array([r.granule_velocity - r.hammer_velocity for r in rows]),
        "tangential_velocity_before": np.zeros(n),
        "tangential_velocity_after": np.zeros(n),
        "normal_impulse": np.array([r.impulse for r in rows]),
        "granule_energy_gain": np.array([r.granule_energy_gain for r in rows]),
        "dissipated": np.array([r.dissipated for r in rows]),
        "hammer_energy_before": np.array([r.hammer_energy_before for r in rows]),
    }
    granules = {k: np.zeros(2 * n + 1) for k in ("id", "x", "y", "vx", "vy", "angular_velocity")}
    granules["time"] = np.arange(2 * n + 1) * 0.5  # frames between impacts: at rest
    granules["speed"] = np.zeros(2 * n + 1)
    case = case.model_copy(update={"granules": case.granules.model_copy(update={"mass": m})})
    return Run(tmp_path, case, {}, granules, {}, impacts, {})


def test_impact_stats_against_two_body_closed_forms(tmp_path: Path) -> None:
    m, M, e = 0.16e-3, 0.02, 0.7
    run = _synthetic_run(tmp_path, m, M, e, [6.6, 3.0])
    s = impact_stats(run, 0)
    model = impact_efficiencies(m, M, e)
    assert s.restitution == pytest.approx(e, rel=1e-12)
    assert s.reduced_mass == pytest.approx(m * M / (m + M), rel=1e-12)
    assert s.normal_loss == pytest.approx(model.hammer_frame_loss, rel=1e-12)
    assert s.transfer == pytest.approx(model.transfer, rel=1e-12)
    assert s.relative == pytest.approx(model.relative, rel=1e-12)
    assert s.dissipated_ratio == pytest.approx(model.dissipated, rel=1e-12)
    assert math.isnan(s.lab_loss)  # at rest before: a gain, no loss fraction
    energies = successive_energies(run)
    assert energies.lab_fraction[1] == pytest.approx((3.0 / 6.6) ** 2, rel=1e-12)
    counts, edges = impact_speed_histogram([s.approach_speed], bins=[0, 5, 10])
    assert counts.tolist() == [0, 1] and edges[-1] == 10


def test_read_table_without_rows(tmp_path: Path) -> None:
    (tmp_path / "t.csv").write_text("time,id\n")
    assert read_table(tmp_path / "t.csv")["time"].size == 0


def test_real_two_body_run_matches_every_efficiency(tmp_path: Path) -> None:
    directory = tmp_path / "run"
    prepare_directory(directory, overwrite=False)
    case_path = CASES / "two-body-impact.toml"
    run_case(load_case(case_path), case_path, directory)
    run = load_run(directory)
    p = efficiency_point(run)
    model = impact_efficiencies(p.granule_mass, p.hammer_mass, p.restitution)
    for name in ("transfer", "relative", "dissipated", "hammer_frame_loss"):
        assert getattr(p, name) == pytest.approx(getattr(model, name), rel=1e-9), name
    assert run.name == "run"  # its directory's, unless labelled
    assert load_run(directory, "two-body-M20g").name == "two-body-M20g"
