"""Granule sizes drawn from a distribution, by number and by mass, against the distribution's own
CDF (scipy.stats) with a Kolmogorov-Smirnov bound, and tables against their fractions."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from perga.case import load_case
from perga.model.sizes import draw_radii, masses

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = (ROOT / "cases" / "bee-bread-separator.toml").read_text()
SIZE = 'size = { kind = "uniform", low = 0.00245, high = 0.00265 }'
N = 20_000
KS = 1.95 / math.sqrt(N)  # the KS statistic's 0.1 % critical value for N draws


def _cut(dist, r):
    """CDF of ``dist`` cut to [2, 3] mm."""
    lo, hi = dist.cdf(0.002), dist.cdf(0.003)
    return (dist.cdf(r) - lo) / (hi - lo)


def _case(tmp_path: Path, size: str):
    path = tmp_path / "case.toml"
    text = BUNDLED.replace(SIZE, size).replace("pitch = 0.0055", "pitch = 0.0065")
    path.write_text(text.replace("../geometry", str(ROOT / "geometry")))
    return load_case(path)


def _draw(tmp_path: Path, size: str) -> np.ndarray:
    case = _case(tmp_path, size)
    return draw_radii(case, N, np.random.default_rng(5))


@pytest.mark.parametrize(
    ("size", "cdf"),
    [
        ('{ kind = "uniform", low = 0.002, high = 0.003 }',
         lambda r: stats.uniform.cdf(r, 0.002, 0.001)),
        ('{ kind = "normal", mean = 0.0025, sd = 0.0002, low = 0.002, high = 0.003 }',
         lambda r: stats.truncnorm.cdf(r, -2.5, 2.5, loc=0.0025, scale=0.0002)),
        ('{ kind = "lognormal", median = 0.0025, sigma = 0.1, low = 0.002, high = 0.003 }',
         lambda r: _cut(stats.lognorm(0.1, scale=0.0025), r)),
    ],
    ids=["uniform", "normal", "lognormal"],
)  # fmt: skip
def test_continuous_sizes_follow_their_distribution(tmp_path, size, cdf) -> None:
    radii = _draw(tmp_path, f"size = {size}")
    assert radii.min() >= 0.002 and radii.max() <= 0.003
    assert stats.kstest(radii, cdf).statistic < KS


def test_uniform_by_mass_weighs_small_granules_more_by_number(tmp_path) -> None:
    """Uniform by mass on [a, b]: the number density ∝ 1/r², CDF (1/a − 1/r)/(1/a − 1/b)."""
    a, b = 0.002, 0.003
    radii = _draw(tmp_path, f'size = {{ kind = "uniform", basis = "mass", low = {a}, high = {b} }}')
    assert stats.kstest(radii, lambda r: (1 / a - 1 / r) / (1 / a - 1 / b)).statistic < KS


@pytest.mark.parametrize(("basis", "share"), [("number", 0.5), ("mass", 0.5 / 4 / (0.5 / 4 + 0.5))])
def test_table_fractions_by_number_and_by_mass(tmp_path, basis, share) -> None:
    """Radii 2 and 1 mm, half and half: by number half the granules are 2 mm; by mass a 2 mm
    granule weighs 4 times a 1 mm one, so their number share is (0.5/4)/(0.5/4 + 0.5) = 0.2.
    Within 4 binomial standard errors."""
    table = (
        f'{{ kind = "table", basis = "{basis}", radii = [0.002, 0.001], fractions = [0.5, 0.5] }}'
    )
    radii = _draw(tmp_path, f"size = {table}")
    assert set(np.unique(radii)) == {0.001, 0.002}
    assert abs(np.mean(radii == 0.002) - share) < 4 * math.sqrt(share * (1 - share) / N)


def test_masses_are_density_area_thickness(tmp_path) -> None:
    case = _case(tmp_path, SIZE)
    r = np.array([0.00245, 0.0026])
    np.testing.assert_allclose(masses(case, r), 1350.0 * math.pi * r**2 * 0.010, rtol=1e-15)


@pytest.mark.parametrize("basis", ["number", "mass"])
def test_feed_rate_by_number_or_by_mass(tmp_path, basis) -> None:
    """A feed of 9-granule comb pieces at 10 per s, or at the mass rate of 10 pieces per s
    (10·9·ρπt·E[r²], E[r²] = (a² + ab + b²)/3 for r uniform on [a, b]): the same items per s,
    to 1e-6 (the mean mass's trapezoid on 4,097 radii)."""
    from perga.model.compile import compile_case

    a, b = 0.00245, 0.00265
    mean_mass = 1350.0 * math.pi * 0.010 * (a * a + a * b + b * b) / 3
    rate = 10.0 if basis == "number" else 10.0 * 9 * mean_mass
    _case(tmp_path, SIZE)  # writes case.toml
    text = (tmp_path / "case.toml").read_text()
    text = text.replace("rate = 10.0", f'rate = {rate!r}\nbasis = "{basis}"')
    (tmp_path / "case.toml").write_text(text)
    case = load_case(tmp_path / "case.toml")
    feed = compile_case(case).process.feed
    assert feed is not None and feed.rate == pytest.approx(10.0, rel=1e-6)
