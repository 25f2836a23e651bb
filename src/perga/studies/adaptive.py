"""An operating window found with few runs (:func:`adaptive_window`): the adaptive alternative to
``perga window``'s brute-force grid of every setting × replicates.

A setting (x, y) of two case keys (e.g. rotor speed in rpm and hammer mass in kg) is inside the
window when its mean ``released_fraction`` ≥ the release target and its mean
``damaged_fraction`` ≤ the damage limit (:func:`perga.studies.window.inside`). The runs: a
coarse grid first (every ``coarse``-th value of each axis, both ends included); then, in rounds,
a batch of runs at the dense grid's cells whose classification is most ambiguous.

Per metric a Gaussian process (Rasmussen & Williams 2006, ch. 2, 4-5: c·Matérn 5/2 with a length
per axis plus white noise for the seed scatter, hyperparameters by maximum marginal likelihood:
the calibration surrogate's :func:`~perga.studies.surrogate.fit_gp`) is fitted to the runs so
far, the axes scaled to [0, 1]; its latent (noise-free) mean μ and sd σ at each dense cell give
the probability the cell is inside, P = Φ((μ_r − target)/σ_r) · Φ((limit − μ_d)/σ_d), the two
metrics taken as independent. The next batch goes where the straddle is largest (Bryan,
Schneider, Nichol, Miller, Genovese & Wasserman, "Active learning for identifying function
threshold boundaries", NIPS 2005): for one threshold t, 1.96σ − |μ − t| = min(U, −L) with U = μ
+ 1.96σ − t and L = μ − 1.96σ − t, positive where the 95 % band straddles t and the larger the
farther it reaches past t on its shorter side. Inside-ness is the level set min(m_r, m_d) ≥ 0 of
the margins m_r = release − target and m_d = limit − damage (both -), so U and L are taken as
the minima over the two margins of their bands' upper and of their lower ends: the joint
classification's straddle, which is the one metric's wherever the other clearly passes (and ≤ 0
wherever the other clearly fails). A batch is picked greedily: after each pick each GP's
covariance is updated as if that run were done (a GP's variance does not depend on the values;
the mean is kept), so a batch spreads along the boundary instead of stacking on one cell; a cell
is picked twice in one batch only when no other cell is open.

A cell is open while its P is in (``tolerance``, 1 − ``tolerance``) (unsettled), or while it is
on the predicted boundary (its class differs from a neighbour's) and has not been run: the GP's
smoothness alone can settle an unrun cell next to a sharp step on the wrong side (a toy step
in the tests did, at P ≈ 0.02, in 3 of 8 noise seeds), so each boundary cell's class rests on
a run of its own. The rounds stop when no cell is open ("tolerance") or the run budget is
spent ("budget"). A cell is classified inside when P ≥ 0.5.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.special import ndtr
from threadpoolctl import threadpool_limits

from perga.studies.surrogate import GpBounds, fit_gp
from perga.studies.window import DAMAGE, RELEASE

Evaluate = Callable[[list[tuple[float, float]]], list[dict[str, float]]]
"""Runs one run per listed setting (x, y) (a setting listed twice: two replicates, each its own
seed) and returns, per run in order, its metrics (at least ``released_fraction`` and
``damaged_fraction``, both -; nan where the run could not give one)."""

STRADDLE_Z = 1.96
"""The band of the straddle, in σ: 95 % two-sided (Bryan et al. 2005)."""


@dataclass(frozen=True)
class AdaptiveResult:
    """An adaptive window: the settings run (x, y in the axes' units) and their metrics, in
    order; the runs and rounds (batches, the coarse grid the first) used; per dense cell (arrays
    shaped (len(ys), len(xs)), x fastest) each metric's GP mean and latent sd (-), the
    probability the cell is inside and its classification (P ≥ 0.5); why the rounds stopped:
    "tolerance" (no cell open: every one settled, each on the boundary run) or "budget" (the
    runs spent)."""

    xs: np.ndarray
    ys: np.ndarray
    settings: list[tuple[float, float]]
    metrics: list[dict[str, float]]
    runs: int
    rounds: int
    mean: dict[str, np.ndarray]
    sd: dict[str, np.ndarray]
    probability: np.ndarray
    inside: np.ndarray
    stopped: Literal["tolerance", "budget"]


def coarse_indices(n: int, coarse: int) -> np.ndarray:
    """Indices of the coarse grid on an axis of ``n`` values: ⌈(n − 1)/coarse⌉ + 1 of them,
    evenly spread (rounded), both ends included (n = 10, coarse = 3: 0, 3, 6, 9)."""
    count = math.ceil((n - 1) / coarse) + 1
    return np.unique(np.round(np.linspace(0, n - 1, count)).astype(int))


def coarse_design(
    xs: Sequence[float], ys: Sequence[float], coarse: int = 3, replicates: int = 1
) -> list[tuple[float, float]]:
    """The first round's settings: the coarse grid (:func:`coarse_indices` on each axis), x
    fastest, each setting ``replicates`` times in a row."""
    return [
        (float(xs[i]), float(ys[j]))
        for j in coarse_indices(len(ys), coarse)
        for i in coarse_indices(len(xs), coarse)
        for _ in range(replicates)
    ]


def _check(
    xs: np.ndarray,
    ys: np.ndarray,
    release_target: float,
    damage_limit: float,
    budget: int,
    tolerance: float,
    batch: int,
    coarse: int,
    replicates: int,
) -> None:
    """ValueError naming each bad argument."""
    problems = []
    for name, values in (("xs", xs), ("ys", ys)):
        if values.ndim != 1 or values.size < 2:
            problems.append(f"{name}: at least 2 values on the axis (got {values.size})")
        elif not (np.all(np.isfinite(values)) and np.all(np.diff(values) > 0)):
            problems.append(f"{name}: finite values, strictly ascending")
    for name, value in (("release_target", release_target), ("damage_limit", damage_limit)):
        if not math.isfinite(value):
            problems.append(f"{name}: a finite fraction (got {value})")
    if not 0.0 < tolerance < 0.5:
        problems.append(f"tolerance: a probability in (0, 0.5) (got {tolerance:g})")
    for name, value in (("batch", batch), ("coarse", coarse), ("replicates", replicates)):
        if value < 1:
            problems.append(f"{name}: at least 1 (got {value})")
    if not problems:
        first = len(coarse_design(xs, ys, coarse, replicates))
        if budget < first:
            problems.append(f"budget: at least the coarse grid's {first} runs (got {budget})")
    if problems:
        raise ValueError("; ".join(problems))


@dataclass(frozen=True)
class _Posterior:
    """One metric's GP at the dense cells: the latent mean (cells,) and covariance (cells,
    cells), and a run's noise variance, all in the metric's units."""

    mean: np.ndarray
    covariance: np.ndarray
    noise: float

    @property
    def sd(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def after_run(self, cell: int) -> _Posterior:
        """This posterior after one more run at ``cell`` (mean kept; the variance does not
        depend on the run's value)."""
        column = self.covariance[:, cell]
        denominator = max(column[cell] + self.noise, 1e-300)
        covariance = self.covariance - np.outer(column, column) / denominator
        return _Posterior(self.mean, covariance, self.noise)


WINDOW_BOUNDS = GpBounds(amplitude=(1e-3, 1e3), length=(5e-2, 1e1), noise=(1e-6, 1.0),
                         noise_start=1e-2)  # fmt: skip
"""The GPs' hyperparameter ranges: the seeds' scatter of a window's metrics is real noise, up to
the metric's own variance."""


def _fit(x: np.ndarray, values: np.ndarray, cells: np.ndarray, seed: int) -> _Posterior:
    """The GP of ``values`` (nan left out) at the runs' scaled settings ``x`` (runs, 2),
    predicted at the scaled ``cells`` (cells, 2) (:func:`perga.studies.surrogate.fit_gp`)."""
    ok = np.isfinite(values)
    # one BLAS thread: on matrices this small more only contend (and the workers share cores)
    with threadpool_limits(1, user_api="blas"):
        gp = fit_gp(x[ok], values[ok], seed, WINDOW_BOUNDS)
        mean, covariance = gp.latent(cells)
    return _Posterior(mean, covariance, gp.run_noise)


def _margins(
    release: _Posterior, damage: _Posterior, release_target: float, damage_limit: float
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """Each metric's margin towards passing (release − target, limit − damage; -) and its sd."""
    return (
        (release.mean - release_target, release.sd),
        (damage_limit - damage.mean, damage.sd),
    )


def _probability(margins: tuple[tuple[np.ndarray, np.ndarray], ...]) -> np.ndarray:
    """P(every margin ≥ 0), the margins normal and independent."""
    p = np.ones_like(margins[0][0])
    for m, s in margins:
        # a margin known exactly (s = 0): ±inf by its sign, 0 (P = ½) on the threshold itself
        sure = np.where(m > 0, np.inf, np.where(m < 0, -np.inf, 0.0))
        z = np.divide(m, s, out=sure, where=s > 0)
        p = p * ndtr(np.nan_to_num(z, nan=0.0))
    return p


def _straddle(margins: tuple[tuple[np.ndarray, np.ndarray], ...]) -> np.ndarray:
    """The joint straddle min(U, −L) of min(margins) ≥ 0 (module doc)."""
    upper = np.min([m + STRADDLE_Z * s for m, s in margins], axis=0)
    lower = np.min([m - STRADDLE_Z * s for m, s in margins], axis=0)
    return np.minimum(upper, -lower)


def _settled(p: np.ndarray, tolerance: float) -> np.ndarray:
    return (p <= tolerance) | (p >= 1.0 - tolerance)


def _boundary(inside: np.ndarray) -> np.ndarray:
    """The cells of a classification (rows y, columns x) whose class differs from one of their
    four neighbours'."""
    edge = np.zeros_like(inside)
    across, down = inside[:, 1:] != inside[:, :-1], inside[1:, :] != inside[:-1, :]
    edge[:, 1:] |= across
    edge[:, :-1] |= across
    edge[1:, :] |= down
    edge[:-1, :] |= down
    return edge


def _open(p: np.ndarray, tolerance: float, run: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """The cells (flat) still to resolve: unsettled, or on the predicted boundary and never run
    (their class should rest on a run of their own, not on the GP's smoothness alone)."""
    boundary = _boundary((p >= 0.5).reshape(shape)).ravel()
    return ~_settled(p, tolerance) | (boundary & ~run)


def _next_batch(
    release: _Posterior,
    damage: _Posterior,
    limits: tuple[float, float],
    tolerance: float,
    run: np.ndarray,
    shape: tuple[int, int],
    size: int,
) -> list[int]:
    """Up to ``size`` open cells (:func:`_open`; ``run``: each cell run yet) by the largest
    joint straddle, greedily (each pick's run assumed done); a cell twice only when no other
    one is open; fewer if the picks so far would leave none open."""
    picks: list[int] = []
    run = run.copy()
    for _ in range(size):
        margins = _margins(release, damage, *limits)
        open_ = _open(_probability(margins), tolerance, run, shape)
        fresh = open_.copy()
        fresh[picks] = False
        candidates = fresh if fresh.any() else open_
        if not candidates.any():
            break
        cell = int(np.argmax(np.where(candidates, _straddle(margins), -np.inf)))
        picks.append(cell)
        run[cell] = True
        release, damage = release.after_run(cell), damage.after_run(cell)
    return picks


def _run(evaluate: Evaluate, settings: list[tuple[float, float]]) -> list[dict[str, float]]:
    """``evaluate``'s metrics for ``settings``, checked to be one dict per setting."""
    metrics = list(evaluate(settings))
    if len(metrics) != len(settings):
        raise ValueError(f"evaluate: {len(metrics)} results for {len(settings)} settings")
    return metrics


def _values(metrics: list[dict[str, float]], key: str) -> np.ndarray:
    """One metric over the runs, nan where a run did not give it."""
    values = np.array([float(m.get(key, math.nan)) for m in metrics], dtype=float)
    values[~np.isfinite(values)] = math.nan
    if np.isfinite(values).sum() < 2:
        raise RuntimeError(f"{key}: fewer than 2 of {len(values)} runs gave it; no GP to fit")
    return values


def adaptive_window(
    xs: Sequence[float],
    ys: Sequence[float],
    evaluate: Evaluate,
    *,
    release_target: float,
    damage_limit: float,
    budget: int,
    tolerance: float = 0.1,
    batch: int = 4,
    coarse: int = 3,
    replicates: int = 1,
    seed: int = 0,
) -> AdaptiveResult:
    """The window on the dense grid ``xs`` × ``ys`` (each ascending, ≥ 2 values, SI) from at
    most ``budget`` runs of ``evaluate`` (module doc): the coarse grid (every ``coarse``-th
    value, ``replicates`` runs each), then rounds of ``batch`` runs until no cell is open (every
    cell's probability of being inside ≤ ``tolerance`` or ≥ 1 − ``tolerance``, with
    0 < tolerance < 0.5, and each cell on the predicted boundary run) or the budget is spent.
    ``release_target`` and ``damage_limit`` are fractions (-); ``seed`` fixes the GP
    optimiser's restarts. ValueError naming each bad argument."""
    x_axis, y_axis = np.asarray(xs, dtype=float), np.asarray(ys, dtype=float)
    _check(x_axis, y_axis, release_target, damage_limit, budget, tolerance, batch, coarse,
           replicates)  # fmt: skip
    shape = (len(y_axis), len(x_axis))
    grid_x, grid_y = np.meshgrid(x_axis, y_axis)
    dense = [(float(x), float(y)) for x, y in zip(grid_x.ravel(), grid_y.ravel(), strict=True)]
    cell_of = {setting: k for k, setting in enumerate(dense)}
    low, span = np.array([x_axis[0], y_axis[0]]), np.array([np.ptp(x_axis), np.ptp(y_axis)])
    cells = (np.array(dense) - low) / span
    settings = coarse_design(x_axis, y_axis, coarse, replicates)
    metrics = _run(evaluate, settings)
    rounds = 1
    while True:
        run = np.zeros(len(dense), dtype=bool)
        run[[cell_of[s] for s in settings]] = True
        x = (np.array(settings) - low) / span
        release = _fit(x, _values(metrics, RELEASE), cells, seed)
        damage = _fit(x, _values(metrics, DAMAGE), cells, seed)
        p = _probability(_margins(release, damage, release_target, damage_limit))
        if not _open(p, tolerance, run, shape).any():
            stopped: Literal["tolerance", "budget"] = "tolerance"
            break
        if len(settings) >= budget:
            stopped = "budget"
            break
        size = min(batch, budget - len(settings))
        limits = (release_target, damage_limit)
        new = [dense[c] for c in _next_batch(release, damage, limits, tolerance, run, shape, size)]
        settings += new
        metrics += _run(evaluate, new)
        rounds += 1
    return AdaptiveResult(
        xs=x_axis,
        ys=y_axis,
        settings=settings,
        metrics=metrics,
        runs=len(settings),
        rounds=rounds,
        mean={RELEASE: release.mean.reshape(shape), DAMAGE: damage.mean.reshape(shape)},
        sd={RELEASE: release.sd.reshape(shape), DAMAGE: damage.sd.reshape(shape)},
        probability=p.reshape(shape),
        inside=(p >= 0.5).reshape(shape),
        stopped=stopped,
    )
