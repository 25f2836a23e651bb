"""The operating window under parameter uncertainty (``perga window --posterior``): at each
setting, D parameter draws θ_d from a calibration's posterior × S seeds each, reduced to the
probability that the setting is inside the window and to each metric's variance split into a
parameter part and a seed part.

Pure functions on arrays: per setting, for each of :data:`~perga.studies.window.METRICS`, an
array of shape (D, S), row d the draw θ_d, column s the seed, nan (any non-finite value) where a
run could not give the value. Units are the metrics' own: ``released_fraction`` (-),
``damaged_fraction`` (-), ``throughput`` (kg/s), ``energy_per_kg`` (J/kg); variances are in
their squares.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perga.studies.window import DAMAGE, ENERGY, METRICS, RELEASE, THROUGHPUT

Z95 = 1.959963984540054
"""The standard normal's 97.5 % quantile: the Wilson interval's z for 95 %."""


@dataclass(frozen=True)
class VarianceSplit:
    """One metric at one setting, by the law of total variance
    Var(Y) = Var_θ(E[Y | θ]) + E_θ[Var(Y | θ)]:

    - ``mean``: the mean over draws of each draw's seed mean (the posterior mean of the metric);
    - ``parameter``: Var_θ(E[Y | θ]), the part due to the parameters (nan with < 2 draws or no
      seed part);
    - ``seed``: E_θ[Var(Y | θ)], the part due to the seed (nan when no draw has 2 seeds);
    - ``draws``: the draws with at least one finite value (the others are left out).
    """

    mean: float
    parameter: float
    seed: float
    draws: int

    @property
    def total(self) -> float:
        """parameter + seed (nan if either is)."""
        return self.parameter + self.seed

    @property
    def first_order(self) -> float:
        """parameter / total: the first-order Sobol index of θ against the seed (Saltelli et
        al., Global Sensitivity Analysis: The Primer, 2008, ch. 4); nan if undefined."""
        return self.parameter / self.total if self.total > 0 else math.nan


def _draw_means(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per draw (row): the count of finite values, their mean (nan with none) and their
    variance, ddof 1 (nan with fewer than 2)."""
    finite = np.isfinite(values)
    n = finite.sum(axis=1)
    filled = np.where(finite, values, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = filled.sum(axis=1) / n
        squares = np.where(finite, (filled - means[:, None]) ** 2, 0.0).sum(axis=1)
        within = np.where(n >= 2, squares / (n - 1), math.nan)
    return n, means, within


def variance_split(values: ArrayLike) -> VarianceSplit:
    """The :class:`VarianceSplit` of one metric's runs, shape (D, S), by one-way random-effects
    ANOVA (Searle, Casella & McCulloch, Variance Components, 1992, ch. 3), each draw with its own
    count n_d of finite seeds:

    - seed part σ²_s = the mean over draws with n_d ≥ 2 of the within-draw variance (ddof 1);
    - parameter part σ²_θ = the variance over draws of the draw means (ddof 1) minus the mean
      over draws of v_d / n_d, v_d the draw's own within-draw variance (σ²_s for a draw with one
      seed), i.e. minus σ²_s / S with S seeds each: the unbiased estimator, **clipped at 0**
      (the difference can come out negative by chance when σ²_θ is small against σ²_s / S).

    With S = 1 the two parts cannot be told apart: seed and parameter are nan."""
    n, means, within = _draw_means(np.asarray(values, dtype=float))
    kept = n > 0
    n, means, within = n[kept], means[kept], within[kept]
    draws = int(means.size)
    multi = n >= 2
    seed = float(within[multi].mean()) if multi.any() else math.nan
    parameter = math.nan
    if draws >= 2 and math.isfinite(seed):
        own = np.where(multi, within, seed)
        parameter = max(0.0, float(np.var(means, ddof=1) - np.mean(own / n)))
    mean = float(means.mean()) if draws else math.nan
    return VarianceSplit(mean, parameter, seed, draws)


def wilson(inside: int, draws: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion ``inside / draws`` (Wilson, JASA 22,
    1927; Brown, Cai & DasGupta, Statistical Science 16, 2001); (nan, nan) with no draws."""
    if draws == 0:
        return math.nan, math.nan
    p = inside / draws
    z2n = z * z / draws
    centre = (p + z2n / 2) / (1 + z2n)
    half = z / (1 + z2n) * math.sqrt(p * (1 - p) / draws + z2n / (4 * draws))
    return max(0.0, centre - half), min(1.0, centre + half)


@dataclass(frozen=True)
class SettingOdds:
    """One setting (x, y: the window's two axis values) under the posterior:

    - ``probability``: the fraction of the ``draws`` draws inside the window (see
      :func:`setting_odds` for what it estimates); ``se`` its binomial standard error
      √(p(1 − p)/D), ``low``, ``high`` its Wilson 95 % interval;
    - ``draws``: D, all the draws (the denominator); ``seeds``: S, the seeds per draw;
      ``missing``: the draws without a release or a damage mean, counted as outside;
    - ``split``: per metric its :class:`VarianceSplit` (mean, parameter and seed variances).
    """

    x: float
    y: float
    probability: float
    se: float
    low: float
    high: float
    draws: int
    seeds: int
    missing: int
    split: dict[str, VarianceSplit]


def setting_odds(
    runs: Mapping[str, ArrayLike],
    release_target: float,
    damage_limit: float,
    x: float = math.nan,
    y: float = math.nan,
) -> SettingOdds:
    """The :class:`SettingOdds` of one setting from its runs: per metric of
    :data:`~perga.studies.window.METRICS` an array of shape (D, S), D ≥ 1, S ≥ 1.

    A draw is inside when its seed-mean release ≥ ``release_target`` and its seed-mean damage ≤
    ``damage_limit`` (both -; the rule of :func:`perga.studies.window.inside`). The probability
    is the fraction of draws inside: an unbiased estimate of
    P_θ~posterior[ r̄_S(θ) ≥ target and d̄_S(θ) ≤ limit ], r̄_S(θ), d̄_S(θ) the means of S
    seeded runs at θ. That is the probability over the posterior of the setting's expected
    metrics being inside, each draw's expectation estimated by the mean of S seeds, so the seed
    noise enters through a variance s²/S (s² the seed variance; with fewer finite seeds in a
    draw, its own count); it tends to P_θ[E(r | θ) ≥ target, E(d | θ) ≤ limit] as S grows.
    ValueError on a missing metric or arrays not all of one shape (D, S)."""
    absent = [m for m in METRICS if m not in runs]
    if absent:
        raise ValueError(f"runs: missing metric(s) {', '.join(absent)}")
    arrays = {m: np.asarray(runs[m], dtype=float) for m in METRICS}
    shape = arrays[RELEASE].shape
    if len(shape) != 2 or min(shape) < 1:
        raise ValueError(f"runs: each metric an array (draws D >= 1, seeds S >= 1), got {shape}")
    odd = [f"{m} {a.shape}" for m, a in arrays.items() if a.shape != shape]
    if odd:
        raise ValueError(f"runs: every metric of shape {shape}; got {', '.join(odd)}")
    draws, seeds = shape
    release = _draw_means(arrays[RELEASE])[1]
    damage = _draw_means(arrays[DAMAGE])[1]
    missing = int(np.count_nonzero(~(np.isfinite(release) & np.isfinite(damage))))
    inside = int(np.count_nonzero((release >= release_target) & (damage <= damage_limit)))
    p = inside / draws
    low, high = wilson(inside, draws)
    split = {m: variance_split(a) for m, a in arrays.items()}
    return SettingOdds(
        x, y, p, math.sqrt(p * (1 - p) / draws), low, high, draws, seeds, missing, split
    )


def best_setting(settings: list[SettingOdds]) -> SettingOdds | None:
    """The setting with the highest probability inside, ties by the higher mean throughput,
    then the lower mean energy per kg (a missing mean ranks last); None if no setting has a
    probability above 0."""

    def rank(s: SettingOdds) -> tuple[float, float, float]:
        t, e = s.split[THROUGHPUT].mean, s.split[ENERGY].mean
        return (
            -s.probability,
            -t if math.isfinite(t) else math.inf,
            e if math.isfinite(e) else math.inf,
        )

    candidates = [s for s in settings if s.probability > 0]
    return min(candidates, key=rank) if candidates else None
