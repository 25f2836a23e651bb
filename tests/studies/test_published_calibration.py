"""The worked calibration against a published experiment: Kharaz, Gorham & Salman (2001),
alumina spheres on a glass anvil (examples/calibration/published/SOURCE.md). Its rows where
the sphere slides throughout give back the published restitution and friction inside the
95 % intervals, from two-fidelity runs; read as the contact point's instead of the centre's,
the same numbers put the friction at a third, the published value far outside."""

from __future__ import annotations

from pathlib import Path

import pytest

from perga.studies.calibrate import calibrate

HERE = Path(__file__).resolve().parents[2] / "examples" / "calibration" / "published"
CASE = HERE / "kharaz2001.toml"
DATA = HERE / "kharaz2001_sliding.csv"
PUBLISHED = {"contacts.alumina-glass.restitution": 0.98, "contacts.alumina-glass.friction": 0.092}
FITS = ["contacts.alumina-glass.restitution=0.5:1", "contacts.alumina-glass.friction=0.01:0.5"]

pytestmark = pytest.mark.slow


def test_the_published_restitution_and_friction_come_back(tmp_path: Path) -> None:
    fit = calibrate(CASE, DATA, FITS, tmp_path / "fit", method="two-fidelity", workers=2).fit
    assert fit.runs <= 100
    for key, (lo, hi) in zip(fit.keys, fit.intervals, strict=True):
        assert lo < PUBLISHED[key] < hi, (key, lo, hi)
    friction = fit.intervals[1]
    assert friction[1] - friction[0] < 0.03  # informative: a third of the value wide at most


def test_the_contact_point_s_reading_misses_the_friction(tmp_path: Path) -> None:
    """The same columns named for the contact point: a disc's slip changes three times as fast
    as its centre's velocity, so the fit's friction is about a third of the published value."""
    swapped = tmp_path / "swapped.csv"
    swapped.write_text(DATA.read_text().replace("_centre", "_contact"))
    fit = calibrate(CASE, swapped, FITS, tmp_path / "fit", method="two-fidelity", workers=2).fit
    lo, hi = fit.intervals[1]
    assert hi < PUBLISHED["contacts.alumina-glass.friction"] / 2, (lo, hi)
