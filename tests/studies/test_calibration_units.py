"""Data files that carry their units and are checked against each metric's bounds
(perga.studies.calibrate.load_data, perga.studies.column_units): a file in degrees and one in
radians load to the same data, and every refusal is tested on both sides of its limit."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from perga.studies.calibrate import FitKey, load_data
from perga.studies.study_file import StudyError

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "rebound-test.toml"
FITS = [FitKey("contacts.granule-hammer.friction", 0.05, 0.8)]
ANGLES = [0.2, 0.7, 1.2]


def _load(tmp_path: Path, header: str, rows: list[str]):
    path = tmp_path / "data.csv"
    path.write_text("\n".join([header, *rows]) + "\n", encoding="utf-8")
    return load_data(path, CASE, FITS)


def test_a_file_in_degrees_loads_as_one_in_radians(tmp_path: Path) -> None:
    """Conditions and a metric (with its sd) in degrees: the same conditions and values to
    rounding (1e-15 relative: one product each), so the same runs and the same fit."""
    beta = [-0.9, -0.8, -0.7]
    rebound = [0.3, 0.5, 0.9]
    radians = _load(
        tmp_path,
        "granules.placement.angle,first_impact_rebound_angle_centre,"
        "first_impact_rebound_angle_centre_sd,first_impact_tangential_restitution_centre",
        [f"{a!r},{r!r},0.01,{b!r}" for a, r, b in zip(ANGLES, rebound, beta, strict=True)],
    )
    degrees = _load(
        tmp_path,
        "granules.placement.angle [deg],first_impact_rebound_angle_centre [deg],"
        "first_impact_rebound_angle_centre_sd [deg],first_impact_tangential_restitution_centre [-]",
        [f"{math.degrees(a)!r},{math.degrees(r)!r},{math.degrees(0.01)!r},{b!r}"
         for a, r, b in zip(ANGLES, rebound, beta, strict=True)],
    )  # fmt: skip
    assert radians.metrics == degrees.metrics
    for a, b in zip(radians.conditions, degrees.conditions, strict=True):
        assert b["granules.placement.angle"] == pytest.approx(a["granules.placement.angle"],
                                                              rel=1e-15)  # fmt: skip
    assert np.allclose(degrees.values, radians.values, rtol=1e-15, atol=0)
    assert np.allclose(degrees.sd[:, 0], radians.sd[:, 0], rtol=1e-15)


@pytest.mark.parametrize(
    ("unit", "accepted"),
    [("deg", True), ("rad", True), ("mm", False), ("furlong", False)],
)
def test_a_unit_must_be_known_and_of_the_metric_s_dimension(tmp_path, unit, accepted) -> None:
    header = f"granules.placement.angle,first_impact_rebound_angle_centre [{unit}]"
    rows = [f"{a!r},0.2" for a in ANGLES]
    if accepted:
        _load(tmp_path, header, rows)
        return
    with pytest.raises(StudyError) as refused:
        _load(tmp_path, header, rows)
    why = "is a unit of length" if unit == "mm" else "unknown unit [furlong]"
    assert why in str(refused.value) and "data.csv: column first_impact_rebound" in str(
        refused.value
    )


@pytest.mark.parametrize(
    ("metric", "value", "remedy"),
    [
        ("first_impact_tangential_restitution_centre", -1.0, None),
        ("first_impact_tangential_restitution_centre", 0.0, None),
        ("first_impact_tangential_restitution_centre", 0.7, "negate the column"),
        ("first_impact_tangential_restitution_centre", -1.02, "another unit"),
        ("first_impact_restitution", 1.0, None),
        ("first_impact_restitution", 1.01, "another unit"),
        ("first_impact_restitution", 0.0, None),
        ("first_impact_restitution", -0.5, "negate the column"),
        ("shot_rebound_angle_centre", 0.0, None),
        ("shot_rebound_angle_centre", 1.5, None),
        ("shot_rebound_angle_centre", -0.3, "negate the column"),
        ("shot_rebound_angle_centre", 1.6, "another unit"),
        ("shot_rebound_angle_contact", -0.3, None),
        ("shot_rebound_angle_contact", -1.6, "another unit"),
    ],
)
def test_values_outside_a_metric_s_bounds_are_refused_with_the_remedy(
    tmp_path, metric, value, remedy
) -> None:
    """β at the centre lies in [−1, 0] for a granule without spin before (a ratio u_t'/u_t,
    the other sign convention, is refused with the hint to negate it); e in [0, 1]; the
    centre's rebound angle forward-positive in [0, π/2] (one measured backward is refused), the
    contact point's in [−π/2, π/2] (its slip may reverse)."""
    rows = [f"{a!r},{value!r}" for a in ANGLES]
    if remedy is None:
        assert _load(tmp_path, f"granules.placement.angle,{metric}", rows).values[0, 0] == value
        return
    with pytest.raises(StudyError) as refused:
        _load(tmp_path, f"granules.placement.angle,{metric}", rows)
    message = str(refused.value)
    assert f"line 2, column {metric}: {value:.6g} is outside" in message and remedy in message


def test_the_sd_of_a_metric_with_an_argument(tmp_path: Path) -> None:
    """``NAME:ARG_sd`` is the sd of ``NAME:ARG`` (not a metric of argument ``ARG_sd``)."""
    path = tmp_path / "struck.csv"
    path.write_text(
        "rotor.rpm,granule_speed_after_impact:1,granule_speed_after_impact:1_sd\n600,11.6,0.05\n"
    )
    data = load_data(path, ROOT / "cases" / "single-granule.toml", FITS)
    assert data.metrics == ["granule_speed_after_impact:1"] and data.sd[0, 0] == 0.05
