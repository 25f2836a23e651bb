"""A calibration's posterior at a DEM user's price: Gaussian-process surrogates of the simulated
metrics over the fitted keys, refined where the posterior lies (:func:`surrogate_posterior`).

Each data row's metric is s(θ) ≈ a(θ) + δ(θ): a cheap model a (none, a = 0; or the analytical
model, :mod:`perga.studies.analytic_metrics`, which makes this a two-fidelity calibration in the
manner of Kennedy & O'Hagan 2001, with an additive discrepancy) and a GP δ fitted to the DEM
runs' s − a (scikit-learn's ``GaussianProcessRegressor``, Matérn ν = 5/2 with a length per key
and a white-noise term for the runs' scatter; Rasmussen & Williams 2006, ch. 4-5). The
likelihood carries the surrogate's own variance: for measured y with sd σ,
log L = −½ Σ [(μ(θ) − y)²/(σ² + σ_GP²(θ)) + log(σ² + σ_GP²(θ))]; without sd columns each
metric's σ is sampled too, with the prior p(σ) ∝ 1/σ. The posterior is sampled by emcee on the
surrogate (cheap: no run).

The runs: a scrambled Halton design over the bounds first; then, in rounds, a batch of vectors
drawn from the current posterior's samples where the surrogate is least sure relative to the
data's noise (greedy: each pick's variance reduction is known before its run, the GP's variance
not depending on the values), as GrainLearning's iterative Bayesian filtering resamples where
the posterior lies (Cheng et al. 2019). A round is checked before it is used: its runs against
the surrogate's predictions made before them. The refinement stops when they agree within
``tolerance`` of the data's sd, or the run budget is spent; then one vector at the posterior's
median is run as the final check.
"""

from __future__ import annotations

import functools
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from scipy.stats import qmc

if TYPE_CHECKING:
    from perga.studies.calibrate import Fit, Model

Cheap = Callable[[np.ndarray], np.ndarray]
"""A cheap model of the simulated metrics: vectors (n, keys) -> values (n, rows, metrics)."""


@dataclass(frozen=True)
class GpBounds:
    """The ranges scikit-learn searches for the kernel's hyperparameters (on values normalised
    to mean 0 and sd 1, inputs scaled to [0, 1]) and the noise it starts from. The default suits
    a calibration's surrogate, whose runs' scatter is small; a metric with seed scatter (the
    operating window) wants a larger noise."""

    amplitude: tuple[float, float] = (1e-4, 1e4)
    length: tuple[float, float] = (1e-2, 1e2)
    noise: tuple[float, float] = (1e-10, 1e-1)
    noise_start: float = 1e-6


def _kernel(keys: int, bounds: GpBounds):
    """The kernel whose hyperparameters scikit-learn fits: c·Matérn 5/2 (a length per key) plus
    white noise, within ``bounds``."""
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    return ConstantKernel(1.0, bounds.amplitude) * Matern(
        length_scale=np.full(keys, 0.5), length_scale_bounds=bounds.length, nu=2.5
    ) + WhiteKernel(bounds.noise_start, bounds.noise)


@dataclass(frozen=True)
class Gp:
    """One fitted GP of normalised values over scaled vectors (Rasmussen & Williams 2006,
    alg. 2.1), its kernel c·Matérn 5/2(lengths) + noise; predictions in numpy, for the
    posterior's many calls."""

    x: np.ndarray
    y: np.ndarray
    """Training values, normalised."""
    amplitude: float
    lengths: np.ndarray
    noise: float
    offset: float
    scale: float
    """The normalisation: value = offset + scale·normalised."""

    def covariance(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """c·Matérn 5/2 between the rows of a and b."""
        d = np.sqrt(np.sum(((a[:, None, :] - b[None, :, :]) / self.lengths) ** 2, axis=-1))
        root5d = math.sqrt(5) * d
        return self.amplitude * (1.0 + root5d + root5d**2 / 3.0) * np.exp(-root5d)

    @functools.cached_property
    def _solved(self) -> tuple[np.ndarray, np.ndarray]:
        """L⁻¹ (K = L Lᵀ, noise on the diagonal) and α = K⁻¹ y."""
        k = self.covariance(self.x, self.x) + self.noise * np.eye(len(self.x))
        inverse = np.linalg.inv(np.linalg.cholesky(k))
        return inverse, inverse.T @ (inverse @ self.y)

    def predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and sd of a new run's value at the scaled vectors ``x`` (the noise included)."""
        inverse, alpha = self._solved
        cross = self.covariance(x, self.x)
        v = cross @ inverse.T
        variance = np.clip(self.amplitude + self.noise - np.sum(v**2, axis=1), 0.0, None)
        return self.offset + self.scale * (cross @ alpha), self.scale * np.sqrt(variance)

    def latent(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mean and covariance of the noise-free values at the scaled vectors ``x`` (in the
        values' units; a new run's variance adds :attr:`run_noise`)."""
        inverse, alpha = self._solved
        cross = self.covariance(x, self.x)
        v = cross @ inverse.T
        covariance = self.covariance(x, x) - v @ v.T
        return self.offset + self.scale * (cross @ alpha), self.scale**2 * covariance

    @property
    def run_noise(self) -> float:
        """A run's noise variance, in the values' units squared."""
        return self.scale**2 * self.noise

    def with_points(self, x: np.ndarray) -> Gp:
        """This GP after runs at ``x`` that gave its own means there (hyperparameters kept)."""
        mean, _ = self.predict(x)
        y = np.concatenate([self.y, (mean - self.offset) / self.scale])
        return Gp(np.vstack([self.x, x]), y, self.amplitude, self.lengths, self.noise,
                  self.offset, self.scale)  # fmt: skip


def fit_gp(x: np.ndarray, values: np.ndarray, seed: int, bounds: GpBounds | None = None) -> Gp:
    """The GP of ``values`` at the scaled vectors ``x``: hyperparameters by maximum marginal
    likelihood within ``bounds`` (default :class:`GpBounds`; scikit-learn, one restart)."""
    from sklearn.exceptions import ConvergenceWarning
    from sklearn.gaussian_process import GaussianProcessRegressor

    offset, scale = float(values.mean()), float(values.std()) or 1.0
    y = (values - offset) / scale
    kernel = _kernel(x.shape[1], bounds or GpBounds())
    gp = GaussianProcessRegressor(kernel, n_restarts_optimizer=1, random_state=seed)
    with warnings.catch_warnings():  # a length at its bound: the metric is flat along it
        warnings.simplefilter("ignore", ConvergenceWarning)
        kernel = gp.fit(x, y).kernel_
    return Gp(x, y, kernel.k1.k1.constant_value, np.atleast_1d(kernel.k1.k2.length_scale),
              kernel.k2.noise_level, offset, scale)  # fmt: skip


@dataclass(frozen=True)
class Surrogate:
    """The GP of every (row, metric) over the fitted keys scaled to [0, 1] (None where fewer
    than two runs gave the metric), and the cheap model they correct."""

    low: np.ndarray
    high: np.ndarray
    shape: tuple[int, ...]
    gps: list[Gp | None]
    cheap: Cheap | None = None

    def scaled(self, thetas: np.ndarray) -> np.ndarray:
        """Vectors scaled to the unit box of the bounds."""
        return (np.atleast_2d(thetas) - self.low) / (self.high - self.low)

    def predict(self, thetas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The surrogate's mean and sd of the metrics at ``thetas``: (n, rows, metrics) each
        (NaN where no run gave the metric)."""
        thetas = np.atleast_2d(thetas)
        x = self.scaled(thetas)
        mean = np.full((len(x), len(self.gps)), math.nan)
        sd = np.full_like(mean, math.nan)
        for k, gp in enumerate(self.gps):
            if gp is not None:
                mean[:, k], sd[:, k] = gp.predict(x)
        base = 0.0 if self.cheap is None else self.cheap(thetas)
        return base + mean.reshape(len(x), *self.shape), sd.reshape(len(x), *self.shape)

    def with_points(self, thetas: np.ndarray) -> Surrogate:
        """The surrogate as it would be after runs at ``thetas``: its sd is what those runs
        would leave, whatever they give (a GP's variance does not depend on the values)."""
        x = self.scaled(thetas)
        gps = [None if gp is None else gp.with_points(x) for gp in self.gps]
        return Surrogate(self.low, self.high, self.shape, gps, self.cheap)


def fit_surrogate(
    thetas: np.ndarray,
    simulated: np.ndarray,
    low: np.ndarray,
    high: np.ndarray,
    cheap: Cheap | None = None,
    seed: int = 0,
) -> Surrogate:
    """GPs of ``simulated`` (n, rows, metrics) less the cheap model's values over ``thetas``
    (n, keys)."""
    thetas = np.atleast_2d(thetas)
    base = np.zeros_like(simulated) if cheap is None else cheap(thetas)
    target = (simulated - base).reshape(len(thetas), -1)
    x = (thetas - low) / (high - low)
    gps: list[Gp | None] = []
    for column in target.T:
        ok = np.isfinite(column)
        gps.append(fit_gp(x[ok], column[ok], seed) if ok.sum() >= 2 else None)
    return Surrogate(low, high, simulated.shape[1:], gps, cheap)


@dataclass
class Round:
    """One round of runs: how many in all after it, the vectors added, and how far their runs
    fell from the surrogate's predictions made before them, in units of the data's sd (the
    largest over the round's runs and metrics; NaN for the first design)."""

    runs: int
    vectors: int
    error: float
    intervals: list[tuple[float, float]] = field(default_factory=list)


def _noise_bounds(measured: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The range of each metric's unknown noise σ (log): 1e-5 to 1 times its largest measured
    magnitude (the prior p(σ) ∝ 1/σ made proper)."""
    top = np.log(np.maximum(np.nanmax(np.abs(measured), axis=0), 1e-12))
    return top + math.log(1e-5), top


def _log_posterior(
    surrogate: Surrogate, measured: np.ndarray, sd: np.ndarray
) -> Callable[[np.ndarray], np.ndarray]:
    """log p(θ | data) on the surrogate, uniform prior over the bounds; where ``sd`` is NaN
    its metric's noise is the vector's extra entries (log σ, one per such metric, log-uniform
    within :func:`_noise_bounds`)."""
    keys = surrogate.low.size
    unknown = ~np.isfinite(sd).all(axis=0)
    noise_low, noise_high = _noise_bounds(measured)
    low = np.concatenate([surrogate.low, noise_low[unknown]])
    high = np.concatenate([surrogate.high, noise_high[unknown]])

    def log_prob(points: np.ndarray) -> np.ndarray:
        inside = np.all((points >= low) & (points <= high), axis=1)
        out = np.full(len(points), -np.inf)
        if not inside.any():
            return out
        mean, spread = surrogate.predict(points[inside, :keys])
        noise = np.broadcast_to(sd, mean.shape).copy()
        noise[:, :, unknown] = np.exp(points[inside, keys:])[:, None, :]
        variance = noise**2 + np.nan_to_num(spread, nan=0.0) ** 2
        r2 = np.where(np.isfinite(mean), (mean - measured) ** 2 / variance + np.log(variance), 1e12)
        out[inside] = -0.5 * r2.reshape(len(r2), -1).sum(axis=1)
        return out

    return log_prob


def sample_posterior(
    surrogate: Surrogate,
    measured: np.ndarray,
    sd: np.ndarray,
    start: np.ndarray,
    seed: int,
    steps: int = 600,
) -> np.ndarray:
    """Posterior samples (n, keys [+ unknown noises as log σ]) on the surrogate by emcee,
    started around ``start``; the first half of the chain is burn-in."""
    import emcee

    keys = surrogate.low.size
    unknown = ~np.isfinite(sd).all(axis=0)
    rng = np.random.default_rng(seed)
    mean, _ = surrogate.predict(start[None, :])
    scatter = np.nanstd(mean[0] - measured, axis=0)
    low, high = _noise_bounds(measured)
    log_noise = np.clip(np.log(np.maximum(scatter, 1e-300)), low + 1.0, high - 1.0)[unknown]
    ndim = keys + int(unknown.sum())
    walkers = max(64, 8 * ndim)
    width = np.concatenate([0.02 * (surrogate.high - surrogate.low), np.full(unknown.sum(), 0.1)])
    centre = np.concatenate([start, log_noise])
    p0 = centre + width * rng.standard_normal((walkers, ndim))
    p0[:, :keys] = np.clip(p0[:, :keys], surrogate.low, surrogate.high)
    sampler = emcee.EnsembleSampler(
        walkers, ndim, _log_posterior(surrogate, measured, sd), vectorize=True
    )
    sampler.random_state = np.random.RandomState(seed).get_state()
    sampler.run_mcmc(p0, steps, progress=False)
    return sampler.get_chain(discard=steps // 2, thin=5, flat=True)


def _next_batch(
    surrogate: Surrogate, candidates: np.ndarray, noise: np.ndarray, size: int
) -> np.ndarray:
    """``size`` vectors among ``candidates`` where the surrogate's variance relative to the
    data's noise, summed over rows and metrics, is largest, greedily (each pick's runs assumed)."""
    picks = []
    for _ in range(size):
        _, spread = surrogate.predict(candidates)
        score = np.nansum((spread / noise) ** 2, axis=(1, 2))
        best = candidates[int(np.argmax(score))]
        picks.append(best)
        surrogate = surrogate.with_points(best[None, :])
    return np.array(picks)


def posterior_intervals(samples: np.ndarray) -> list[tuple[float, float]]:
    """Each column's 95 % interval: its 2.5 and 97.5 percentiles."""
    return [(float(a), float(b)) for a, b in np.percentile(samples, [2.5, 97.5], axis=0).T]


def minimum_runs(keys: int, rows: int) -> int:
    """The fewest runs a surrogate posterior takes: keys + 1 vectors for its first design and
    one for its check, each a run per data row."""
    return (keys + 2) * rows


def surrogate_posterior(
    model: Model,
    runs: int = 100,
    cheap: Cheap | None = None,
    tolerance: float = 0.25,
    seed: int = 0,
) -> tuple[Fit, list[Round]]:
    """The posterior of ``model``'s fitted keys from at most ``runs`` runs (module doc): the fit
    (values: the posterior's median; intervals: its 2.5-97.5 %; band: the surrogate's
    predictions at the posterior's samples) and the rounds of runs."""
    from perga.studies.calibrate import Fit

    rows = len(model.data.conditions)
    low = np.array([f.low for f in model.fits])
    high = np.array([f.high for f in model.fits])
    keys = low.size
    if runs < minimum_runs(keys, rows):
        raise ValueError(f"{runs} runs: at least {minimum_runs(keys, rows)} needed")
    budget = runs // rows - 1  # vectors, less the final check's
    first = min(budget, 3 * keys if cheap is None else keys + 1)
    batch = max(1, math.ceil(keys / 2))
    measured, sd = model.data.values, model.data.sd
    design = qmc.Halton(keys, scramble=True, seed=seed).random(first)
    thetas = low + design * (high - low)
    simulated = model.evaluate(thetas)
    rounds = [Round(model.runs, len(thetas), math.nan)]
    while True:
        surrogate = fit_surrogate(thetas, simulated, low, high, cheap, seed)
        best = thetas[int(np.argmin([np.sum(model.residuals(s) ** 2) for s in simulated]))]
        samples = sample_posterior(surrogate, measured, sd, best, seed)
        rounds[-1].intervals = posterior_intervals(samples[:, :keys])
        noise = _noise(sd, samples, keys)
        size = min(batch, budget - len(thetas))
        if size <= 0 or (len(rounds) > 1 and rounds[-1].error <= tolerance):
            break
        picks = _next_batch(surrogate, samples[:: max(1, len(samples) // 500), :keys], noise, size)
        predicted, _ = surrogate.predict(picks)
        new = model.evaluate(picks)
        thetas, simulated = np.vstack([thetas, picks]), np.concatenate([simulated, new])
        error = float(np.nanmax(np.abs(new - predicted) / noise))
        rounds.append(Round(model.runs, len(thetas), error))
    median = np.median(samples[:, :keys], axis=0)
    predicted, _ = surrogate.predict(median[None, :])
    check = model.evaluate(median[None, :])[0]
    residuals = model.residuals(check)
    subset = samples[np.random.default_rng(seed).choice(len(samples), min(500, len(samples)))]
    band = np.nanpercentile(surrogate.predict(subset[:, :keys])[0], [2.5, 97.5], axis=0)
    unknown = ~np.isfinite(sd).all(axis=0)
    fit = Fit(
        method="surrogate (GP)" if cheap is None else "two-fidelity (analytic + GP)",
        keys=[f.key for f in model.fits],
        values=[float(v) for v in median],
        standard_errors=[float(s) for s in samples[:, :keys].std(axis=0)],
        intervals=posterior_intervals(samples[:, :keys]),
        residuals=residuals.reshape(measured.shape).tolist(),
        rss=float(residuals @ residuals),
        noise=np.exp(np.median(samples[:, keys:], axis=0)).tolist() if unknown.any() else None,
        evaluations=len(thetas) + 1,
        runs=model.runs,
        band=np.moveaxis(band, 0, -1).tolist(),
        samples=samples[:, :keys].tolist(),
    )
    error = float(np.nanmax(np.abs(check - predicted[0]) / noise[0]))
    rounds.append(Round(model.runs, len(thetas) + 1, error))
    return fit, rounds


def _noise(sd: np.ndarray, samples: np.ndarray, keys: int) -> np.ndarray:
    """The data's sd, (1, rows, metrics): given, or the posterior median of each unknown one."""
    unknown = ~np.isfinite(sd).all(axis=0)
    noise = np.where(np.isfinite(sd), sd, 1.0)
    if unknown.any():
        noise[:, unknown] = np.exp(np.median(samples[:, keys:], axis=0))
    return noise[None, :, :]
