"""Study designs: grid, Latin hypercube and Sobol points over the parameters' ranges."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from perga.studies.design import axis, points
from perga.studies.jobs import derived_seed, make_job, toml_value
from perga.studies.study_file import Parameter, Study

CASE = Path(__file__).resolve().parents[2] / "cases" / "rebound-test.toml"


def _study(design: str, **parameters: Parameter) -> Study:
    return Study(case=CASE, parameters=parameters, design=design, samples=32, seed=3,
                 metrics=["impact_count"])  # fmt: skip


def test_grid_is_the_full_product() -> None:
    study = _study("grid", a=Parameter(values=[1, 2, 3]), b=Parameter(range=(0.1, 0.3), points=2))
    got = points(study)
    assert len(got) == 6
    assert {(p["a"], p["b"]) for p in got} == {(a, b) for a in (1, 2, 3) for b in (0.1, 0.3)}


def test_log_axis() -> None:
    np.testing.assert_allclose(axis(Parameter(range=(1e-3, 1e-1), points=3, scale="log")),
                               [1e-3, 1e-2, 1e-1], rtol=1e-12)  # fmt: skip


@pytest.mark.parametrize("design", ["lhs", "sobol"])
def test_space_filling_designs_stay_in_bounds_and_fill_them(design: str) -> None:
    """32 points in [0.1, 0.5] × [10, 1000] (log): inside the bounds, and a Latin hypercube has
    exactly one point in each of 32 equal strata of each axis (in log space for the log one)."""
    study = _study(design, a=Parameter(range=(0.1, 0.5)),
                   b=Parameter(range=(10.0, 1000.0), scale="log"))  # fmt: skip
    pts = points(study)
    a = np.array([p["a"] for p in pts])
    b = np.array([p["b"] for p in pts])
    assert len(pts) == 32 and np.all((a >= 0.1) & (a <= 0.5)) and np.all((b >= 10) & (b <= 1000))
    if design == "lhs":
        for u in ((a - 0.1) / 0.4, np.log(b / 10) / np.log(100)):
            assert sorted(np.floor(u * 32).astype(int)) == list(range(32))
    assert points(study) == pts  # seeded


def test_values_need_a_grid() -> None:
    with pytest.raises(ValueError, match="give every parameter a range"):
        _study("lhs", a=Parameter(values=[1.0]))


def test_jobs_are_keyed_by_their_resolved_case() -> None:
    """Two spellings of the same run have one key; another value, another key; a replicate
    seed differs from the next and does not depend on the point."""
    root = Path("/tmp/unused")
    a = make_job(CASE, {"contacts.granule-hammer.friction": 0.3}, 0, 1, ("impact_count",), root)
    b = make_job(CASE, {"contacts[0].friction": 0.3}, 0, 1, ("impact_count",), root)
    c = make_job(CASE, {"contacts[0].friction": 0.31}, 0, 1, ("impact_count",), root)
    assert a.key == b.key != c.key
    assert derived_seed(0, 0) != derived_seed(0, 1) and derived_seed(0, 1) == derived_seed(0, 1)
    assert toml_value(0.1) == "0.1" and toml_value(True) == "true" and toml_value("x") == '"x"'
