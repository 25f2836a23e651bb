"""perga window --posterior: on a toy model with known closed forms (release and damage linear in
normal parameters plus normal seed noise), the probability inside the window and the variance
split are recovered within their sampling error; nan draws, one seed, S = 1, the ≥ / ≤ edges
and the best setting's tie rules on hand-built data."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal, norm

from perga.studies.window import DAMAGE, ENERGY, METRICS, RELEASE, THROUGHPUT
from perga.studies.window_posterior import (
    SettingOdds,
    VarianceSplit,
    best_setting,
    setting_odds,
    variance_split,
    wilson,
)

D, S = 4000, 3
TARGET, LIMIT = 0.8, 0.05
MU, SIGMA = 1.0, 0.1  # θ ~ N(MU, SIGMA²)
MU2, SIGMA2 = 2.0, 0.2  # θ' ~ N(MU2, SIGMA2²), independent of θ
B, S_R = 1.0, 0.1  # release = a + B θ + ε, ε ~ N(0, S_R²): parameter part B²σ² = seed part = 0.01
DD, S_D = 0.02, 0.004  # damage = c + DD θ' + ε', ε' ~ N(0, S_D²)
SD_R = math.sqrt(B**2 * SIGMA**2 + S_R**2 / S)  # sd of a draw's seed-mean release over θ
SD_D = math.sqrt(DD**2 * SIGMA2**2 + S_D**2 / S)


def _toy(a: float, c: float, seed: int, *, shared: bool = False) -> dict[str, np.ndarray]:
    """D draws × S seeds of the toy model (θ' = θ when ``shared``), vectorised."""
    rng = np.random.default_rng(seed)
    theta = rng.normal(MU, SIGMA, D)
    theta2 = theta if shared else rng.normal(MU2, SIGMA2, D)
    release = a + B * theta[:, None] + rng.normal(0.0, S_R, (D, S))
    damage = c + DD * theta2[:, None] + rng.normal(0.0, S_D, (D, S))
    return {
        RELEASE: release,
        DAMAGE: damage,
        THROUGHPUT: 0.5 + 0.1 * theta[:, None] + rng.normal(0.0, 0.01, (D, S)),
        ENERGY: 100.0 + rng.normal(0.0, 1.0, (D, S)),
    }


def _offsets(p: float) -> tuple[float, float]:
    """Intercepts a, c making each metric's closed form √p, so the joint one is p."""
    z = norm.ppf(math.sqrt(p))
    return TARGET - B * MU + z * SD_R, LIMIT - DD * MU2 - z * SD_D


def _closed_form(a: float, c: float) -> float:
    """Φ((a + Bμ − t)/SD_R) · Φ((l − c − DDμ')/SD_D): independent θ, θ'."""
    return float(norm.cdf((a + B * MU - TARGET) / SD_R) * norm.cdf((LIMIT - c - DD * MU2) / SD_D))


def _binomial_se(p: float) -> float:
    return math.sqrt(p * (1 - p) / D)


@pytest.mark.parametrize(("p", "seed"), [(0.1, 1), (0.5, 2), (0.9, 3)])
def test_probability_matches_the_closed_form(p: float, seed: int) -> None:
    a, c = _offsets(p)
    exact = _closed_form(a, c)
    assert exact == pytest.approx(p, abs=1e-12)
    odds = setting_odds(_toy(a, c, seed), TARGET, LIMIT)
    print(f"closed form {exact:.4f}, estimated {odds.probability:.4f} ± {odds.se:.4f}")
    assert (odds.draws, odds.seeds, odds.missing) == (D, S, 0)
    assert abs(odds.probability - exact) < 4 * _binomial_se(exact)
    assert odds.se == pytest.approx(_binomial_se(odds.probability))
    assert odds.low < exact < odds.high


def test_probability_with_one_shared_parameter_matches_the_bivariate_normal() -> None:
    """θ' = θ: (r̄, d̄) is bivariate normal with covariance B·DD·σ², so the joint closed form
    is P(−r̄ ≤ −t, d̄ ≤ l) of one bivariate normal (scipy's cdf, accurate to ~1e-5)."""
    a, c = TARGET - B * MU + 0.3 * SD_R, LIMIT - DD * MU - 0.5 * SD_D
    cov = [
        [SD_R**2, -B * DD * SIGMA**2],
        [-B * DD * SIGMA**2, DD**2 * SIGMA**2 + S_D**2 / S],
    ]
    exact = float(multivariate_normal([-(a + B * MU), c + DD * MU], cov).cdf([-TARGET, LIMIT]))
    odds = setting_odds(_toy(a, c, 4, shared=True), TARGET, LIMIT)
    print(f"shared θ: closed form {exact:.4f}, estimated {odds.probability:.4f}")
    assert abs(odds.probability - exact) < 4 * _binomial_se(exact)


def test_variance_split_recovers_the_parameter_and_seed_parts() -> None:
    """Tolerances, 4 sampling sd each: the seed part pools D(S − 1) degrees of freedom, so its
    relative sd is √(2/(D(S − 1))); the parameter part is a sample variance over D draw means
    (relative sd √(2/(D − 1)) of B²σ² + s²/S) less the seed part / S. Both parts are 0.01, so
    forgetting the /S correction (bias s²(1 − 1/S)) or applying it twice are far outside."""
    a, c = _offsets(0.5)
    split = setting_odds(_toy(a, c, 5), TARGET, LIMIT).split[RELEASE]
    seed_tol = 4 * S_R**2 * math.sqrt(2 / (D * (S - 1)))
    param_tol = 4 * SD_R**2 * math.sqrt(2 / (D - 1)) + seed_tol / S
    print(f"parameter {split.parameter:.5f} (B²σ² {B**2 * SIGMA**2:.5f} ± {param_tol:.5f}),")
    print(f"seed {split.seed:.5f} (s² {S_R**2:.5f} ± {seed_tol:.5f})")
    assert split.seed == pytest.approx(S_R**2, abs=seed_tol)
    assert split.parameter == pytest.approx(B**2 * SIGMA**2, abs=param_tol)
    assert split.total == pytest.approx(split.parameter + split.seed)
    assert split.first_order == pytest.approx(0.5, abs=0.05)
    assert split.mean == pytest.approx(a + B * MU, abs=4 * SD_R / math.sqrt(D))
    assert split.draws == D


def test_variance_split_by_hand_with_nan_draws_and_one_seed() -> None:
    """Draw means 2, 6, (all nan: left out), 4; within-draw variances 2, 2, -, (one seed):
    seed part 2; parameter part var(2, 6, 4) − mean(2/2, 2/2, 2/1) = 4 − 4/3."""
    split = variance_split([[1.0, 3.0], [5.0, 7.0], [np.nan, np.nan], [4.0, np.nan]])
    assert split == VarianceSplit(mean=4.0, parameter=pytest.approx(8 / 3), seed=2.0, draws=3)


def test_variance_split_clips_a_negative_parameter_part_at_zero() -> None:
    # draw means 1, 1: their variance 0 less the seed part 2 / 2
    assert variance_split([[0.0, 2.0], [2.0, 0.0]]).parameter == 0.0


def _hand_runs(release: list[list[float]], damage: list[list[float]]) -> dict[str, np.ndarray]:
    shape = np.shape(release)
    return {
        RELEASE: np.array(release),
        DAMAGE: np.array(damage),
        THROUGHPUT: np.ones(shape),
        ENERGY: np.ones(shape),
    }


def test_all_nan_draws_count_as_outside_and_are_reported() -> None:
    nan = np.nan
    runs = _hand_runs(
        [[0.9, 0.9], [nan, nan], [0.9, nan], [0.9, 0.9]],
        [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [nan, nan]],
    )
    odds = setting_odds(runs, TARGET, LIMIT)
    assert (odds.probability, odds.draws, odds.missing) == (0.5, 4, 2)
    assert odds.split[RELEASE].draws == 3
    assert odds.split[DAMAGE].draws == 3


def test_one_seed_per_draw_gives_no_split_but_a_probability() -> None:
    runs = _hand_runs([[0.9], [0.7], [0.85], [0.95]], [[0.0], [0.0], [0.1], [0.0]])
    odds = setting_odds(runs, TARGET, LIMIT)
    assert (odds.probability, odds.seeds) == (0.5, 1)
    split = odds.split[RELEASE]
    assert math.isnan(split.seed) and math.isnan(split.parameter) and math.isnan(split.total)
    assert split.mean == pytest.approx(0.85)


def test_metrics_exactly_at_the_limits_are_inside() -> None:
    """Release mean exactly the target, damage mean exactly the limit (values exact in binary,
    so are their means): inside; a hair outside either: outside."""
    target, limit = 0.75, 0.0625
    low, high = np.nextafter(target, 0.0), np.nextafter(limit, 1.0)
    runs = _hand_runs(
        [[0.75, 0.75], [0.5, 1.0], [0.75, 0.75], [low, low]],
        [[0.0625, 0.0625], [0.0, 0.125], [high, high], [0.0, 0.0]],
    )
    assert setting_odds(runs, target, limit).probability == 0.5


def test_bad_runs_are_refused() -> None:
    runs = _hand_runs([[0.9, 0.9]], [[0.0, 0.0]])
    with pytest.raises(ValueError, match="energy_per_kg"):
        setting_odds({m: runs[m] for m in METRICS[:3]}, TARGET, LIMIT)
    with pytest.raises(ValueError, match=r"damaged_fraction \(2,\)"):
        setting_odds({**runs, DAMAGE: np.zeros(2)}, TARGET, LIMIT)
    with pytest.raises(ValueError, match=r"\(0, 2\)"):
        setting_odds({m: np.zeros((0, 2)) for m in METRICS}, TARGET, LIMIT)


def test_wilson_interval() -> None:
    # Brown, Cai & DasGupta's example values: 0/10 and 5/10 at 95 %
    assert wilson(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    assert wilson(5, 10) == pytest.approx((0.2366, 0.7634), abs=1e-4)
    assert all(math.isnan(v) for v in wilson(0, 0))


def _odds(x: float, p: float, throughput: float, energy: float) -> SettingOdds:
    split = {m: VarianceSplit(1.0, 0.0, 0.0, 10) for m in METRICS}
    split[THROUGHPUT] = VarianceSplit(throughput, 0.0, 0.0, 10)
    split[ENERGY] = VarianceSplit(energy, 0.0, 0.0, 10)
    return SettingOdds(x, 0.0, p, 0.0, 0.0, 1.0, 10, 1, 0, split)


def test_best_setting_and_its_tie_rules() -> None:
    nan = math.nan
    assert best_setting([_odds(0, 0.6, 1.0, 1.0), _odds(1, 0.7, 0.1, 9.0)]).x == 1
    # same probability: the higher throughput; same throughput: the lower energy per kg
    assert best_setting([_odds(0, 0.7, 1.0, 1.0), _odds(1, 0.7, 2.0, 9.0)]).x == 1
    assert best_setting([_odds(0, 0.7, 2.0, 1.0), _odds(1, 0.7, 2.0, 9.0)]).x == 0
    # a missing mean ranks last
    assert best_setting([_odds(0, 0.7, nan, 1.0), _odds(1, 0.7, 0.1, 9.0)]).x == 1
    assert best_setting([_odds(0, 0.7, 1.0, nan), _odds(1, 0.7, 1.0, 9.0)]).x == 1
    # nothing with a probability above 0
    assert best_setting([_odds(0, 0.0, 1.0, 1.0)]) is None
    assert best_setting([]) is None
