"""``perga calibrate``: fit case parameters to measured data, every evaluation a set of runs on
the Dask layer of the sweeps (:mod:`perga.studies.executor`).

The data file (CSV) has one row per measured condition. Its columns are condition keys (case
keys that differ per row, e.g. ``granules.placement.angle``) and metric names
(:mod:`perga.stats.metrics`), with an optional ``NAME_sd`` column giving each value's standard
deviation. Each row is simulated with its conditions and the fitted keys' values; the residuals
are (simulated − measured)/sd (sd = 1 where none is given).

Four methods:

* ``least-squares``: ``scipy.optimize.least_squares`` (trust-region reflective, within the
  bounds) with a forward-difference Jacobian whose runs go to the cluster in one batch. The
  standard errors come from the covariance s²(JᵀJ)⁻¹ at the optimum (s² = RSS/(n − p), or 1
  when every value has its sd: a χ² fit); the intervals are ±t(0.975, n − p) standard errors
  (95 %, linearised).
* ``bayes``: emcee's affine-invariant ensemble sampler (Goodman & Weare 2010) with a uniform
  prior over the bounds and the Gaussian likelihood of the residuals (without sd columns the
  noise is the least-squares estimate s, stated in fit.json), started around the least-squares
  optimum; each step's walkers run as one batch. The 95 % intervals are the posterior's 2.5 and
  97.5 percentiles. docs/dev/calibration.md says why emcee.

* ``surrogate`` and ``two-fidelity``: the posterior from at most ``runs`` runs, sampled on
  Gaussian-process surrogates of the metrics refined where the posterior lies; the second
  corrects the analytical model (a shot's oblique-impact law) with a GP discrepancy
  (:mod:`perga.studies.surrogate`).

Every method writes its posterior sample, ``posterior.parquet`` (a column per fitted key; the
least-squares one drawn from its linearised normal N(θ̂, s²(JᵀJ)⁻¹) within the bounds), which
``perga window --posterior`` draws its parameter sets from.

Runs of an evaluation are study runs like any other (keyed by their resolved case, each
leaving its row in its directory): the same command run again in the same folder replays the
method, every run found finished read back instead of run, so a calibration stopped midway
(Ctrl-C, a killed process) goes on where it stopped and ends with the fit, and for ``bayes`` the
chain, an uninterrupted one gives; repeated points cost nothing.
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import tomli_w
from distributed import Client
from scipy import optimize, stats

from perga import __version__
from perga.case.load import overridden, read_case_data
from perga.case.overrides import NumberTooLong, OverrideError, parse_value, split_override
from perga.stats.metrics import METRICS
from perga.studies.analytic_metrics import NoAnalyticModelError, analytic_model
from perga.studies.column_units import split_unit, to_si
from perga.studies.executor import BatchCluster, dask_client, run_missing
from perga.studies.jobs import Job, derived_seed, make_job, run_job, toml_value
from perga.studies.study_file import StudyError, check_keys, check_metrics
from perga.studies.surrogate import (
    Round,
    minimum_runs,
    posterior_intervals,
    surrogate_posterior,
)

SD_SUFFIX = "_sd"


@dataclass(frozen=True)
class Data:
    """Measured conditions: each row's condition values (case key -> value), the metrics, the
    measured values (rows, metrics) and their standard deviations (nan: not given)."""

    path: Path
    conditions: list[dict[str, Any]]
    metrics: list[str]
    values: np.ndarray
    sd: np.ndarray

    @property
    def weighted(self) -> bool:
        """Whether every value has its standard deviation."""
        return bool(np.all(np.isfinite(self.sd)))


@dataclass(frozen=True)
class FitKey:
    """A fitted case key and its bounds."""

    key: str
    low: float
    high: float


def parse_fit(text: str, where: str = "--fit") -> FitKey:
    """``KEY=LO:HI`` -> a :class:`FitKey` (StudyError naming what is wrong)."""
    key, sep, bounds = text.partition("=")
    low, sep2, high = bounds.partition(":")
    try:
        lo, hi = float(low), float(high)
    except ValueError:
        lo = hi = math.nan
    if not (sep and sep2 and key.strip()) or not (math.isfinite(lo) and math.isfinite(hi)):
        raise StudyError(
            [
                f"{where} {text!r}: expected KEY=LO:HI, e.g. contacts.granule-hammer."
                "restitution=0.4:0.95"
            ]
        )
    if not lo < hi:
        raise StudyError([f"{where} {text!r}: the range needs LO < HI (got {lo} and {hi})"])
    return FitKey(key.strip(), lo, hi)


def _finite(text: str) -> float:
    """``text`` as a finite float, NaN if it is not one."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        return math.nan
    return value if math.isfinite(value) else math.nan


def _condition(text: str, factor: float) -> Any:
    """A condition cell as the case takes it: a number in a column with a unit, to SI."""
    value = parse_value(text)
    if factor != 1.0 and isinstance(value, int | float) and not isinstance(value, bool):
        return value * factor
    return value


def _out_of_bounds(metric: str, value: float) -> str | None:
    """Why a measured ``value`` of ``metric`` (SI) cannot be, or None (its bounds)."""
    m = METRICS[metric.partition(":")[0]]
    if m.bounds is None or m.bounds[0] <= value <= m.bounds[1]:
        return None
    low, high = m.bounds
    flipped = low <= -value <= high
    return (
        f"{value:.6g} is outside [{low:.6g}, {high:.6g}] ({m.convention})"
        + ("; its negative is inside: data of the other sign convention? negate the column"
           if flipped else "; data in another unit? give it in brackets: NAME [UNIT]")
    )  # fmt: skip


def load_data(path: str | Path, case: Path, fits: list[FitKey]) -> Data:
    """The data file, checked against the case (StudyError listing every problem: a metric
    that does not exist, a row of the wrong length, a condition column that is not a case key
    or a row whose values the case refuses, a value that is not a finite number or lies outside
    its metric's bounds, an sd that is not a finite number > 0, a unit unknown or of another
    dimension). Columns may carry their units, ``NAME [UNIT]`` (:mod:`~perga.studies.
    column_units`): values are converted to SI."""
    path = Path(path)
    try:
        with path.open(encoding="utf-8", newline="") as stream:
            columns, *cells = list(csv.reader(stream)) or [[]]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise StudyError([f"{path}: cannot read ({exc})"]) from None
    lines = [(i, row) for i, row in enumerate(cells, start=2) if any(c.strip() for c in row)]
    if not lines:
        raise StudyError([f"{path}: no rows (a header and one row per measured condition)"])
    header = [split_unit(c) for c in columns]
    columns = [name for name, _ in header]
    named = [c for c in columns if c]
    if len(set(named)) != len(columns):
        raise StudyError([f"{path}: line 1: every column needs a name of its own ({columns})"])
    short = [i for i, row in lines if len(row) != len(columns)]
    if short:
        raise StudyError(
            [f"{path}: line {i}: {len(columns)} cells expected, as in the header" for i in short]
        )
    table = [(i, dict(zip(columns, row, strict=True))) for i, row in lines]
    sds = [c for c in columns if c.endswith(SD_SUFFIX) and c[: -len(SD_SUFFIX)] in columns]
    metrics = [c for c in columns if c.partition(":")[0] in METRICS and c not in sds]
    sds = [c for c in sds if c[: -len(SD_SUFFIX)] in metrics]
    conditions = [c for c in columns if c not in metrics and c not in sds]
    problems = []
    factors: dict[str, float] = {}
    for name, unit in header:
        base = name.removesuffix(SD_SUFFIX) if name in sds else name
        metric = METRICS.get(base.partition(":")[0]) if base in metrics else None
        try:
            factors[name] = to_si(unit, metric.unit if metric else None)
        except ValueError as exc:
            problems.append(f"{path}: column {name} [{unit}]: {exc}")
    if not metrics:
        problems.append(f"{path}: no metric column; metric names: {', '.join(METRICS)}")
    problems += check_metrics(metrics, f"{path}: column")
    fitted = {f.key for f in fits}
    problems += [
        f"{path}: column {c}: a fitted key cannot be a condition" for c in conditions if c in fitted
    ]
    values, sd = (
        np.full((len(table), len(metrics)), math.nan),
        np.full_like(np.zeros((len(table), len(metrics))), math.nan),
    )
    rows: list[dict[str, Any]] = []
    for k, (i, record) in enumerate(table):
        try:
            rows.append({c: _condition(record[c], factors.get(c, 1.0)) for c in conditions})
        except NumberTooLong as exc:
            problems.append(f"{path}: line {i}, condition columns: {exc}")
            continue
        for j, m in enumerate(metrics):
            values[k, j] = _finite(record[m]) * factors.get(m, 1.0)
            if not math.isfinite(values[k, j]):
                problems.append(
                    f"{path}: line {i}, column {m}: not a finite number ({record[m]!r})"
                )
            elif reason := _out_of_bounds(m, values[k, j]):
                problems.append(f"{path}: line {i}, column {m}: {reason}")
            if f"{m}{SD_SUFFIX}" in record:
                sd[k, j] = _finite(record[f"{m}{SD_SUFFIX}"]) * factors.get(f"{m}{SD_SUFFIX}", 1.0)
                if not sd[k, j] > 0:  # NaN (not a finite number) fails too
                    problems.append(
                        f"{path}: line {i}, column {m}{SD_SUFFIX}: must be a finite number > 0 "
                        f"({record[f'{m}{SD_SUFFIX}']!r})"
                    )
    fitted = {f.key: f.low for f in fits}
    if not problems:  # every distinct condition, as the runs will set it
        seen: list[dict[str, Any]] = []
        for (i, _), row in zip(table, rows, strict=True):
            if row not in seen:
                seen.append(row)
                where = f"{path}: line {i}, condition columns" if row else f"{path}: --fit"
                problems += check_keys(case, {**row, **fitted}, where)
    if problems:
        raise StudyError(problems)
    return Data(path, rows, metrics, values, sd)


@dataclass
class Model:
    """The simulated metrics of every data row for a vector of the fitted keys, evaluated in
    batches on a Dask client; counts the runs it asked for (``runs``) and those it ran
    (``ran``: the others were found finished, :func:`perga.studies.executor.run_missing`)."""

    case: Path
    data: Data
    fits: list[FitKey]
    directory: Path
    client: Client
    function: Callable[[Job], dict[str, Any]] = run_job
    progress: Callable[[str], None] | None = None
    runs: int = 0
    ran: int = 0
    cache: dict[tuple[float, ...], np.ndarray] = field(default_factory=dict)
    best: tuple[float, tuple[float, ...]] = (math.inf, ())
    """The smallest sum of squared residuals evaluated so far, and its vector."""

    def jobs(self, theta: np.ndarray) -> list[Job]:
        """The runs of one vector: one per data row."""
        fitted = {f.key: float(v) for f, v in zip(self.fits, theta, strict=True)}
        return [
            make_job(
                self.case,
                {**row, **fitted},
                0,
                derived_seed(0, 0),
                tuple(self.data.metrics),
                self.directory,
            )
            for row in self.data.conditions
        ]

    def evaluate(self, thetas: np.ndarray) -> np.ndarray:
        """Simulated metrics (n_theta, rows, metrics); nan where a run gave none."""
        thetas = np.atleast_2d(thetas)
        todo = {tuple(map(float, t)) for t in thetas} - set(self.cache)
        jobs = {key: self.jobs(np.array(key)) for key in todo}
        flat = {j.key: j for js in jobs.values() for j in js}
        rows: dict[str, dict[str, Any]] = {}
        self.ran += run_missing(
            list(flat.values()),
            lambda r: rows.__setitem__(r["key"], r),
            client=self.client,
            function=self.function,
        )
        self.runs += len(flat)
        for key, js in jobs.items():
            self.cache[key] = np.array(
                [[_value(rows[j.key], m) for m in self.data.metrics] for j in js]
            )
            rss = float(np.sum(self.residuals(self.cache[key]) ** 2))
            self.best = min(self.best, (rss, key))
        if self.progress is not None and jobs:
            rss, key = self.best
            values = ", ".join(f"{f.key} = {v:.6g}" for f, v in zip(self.fits, key, strict=True))
            self.progress(
                f"calibrate: {self.runs} runs ({self.ran} run now), {len(self.cache)} parameter "
                f"vectors; best so far {values} (sum of squared residuals {rss:.4g})"
            )
        return np.stack([self.cache[tuple(map(float, t))] for t in thetas])

    def residuals(self, simulated: np.ndarray) -> np.ndarray:
        """(simulated − measured)/sd, flattened (sd = 1 where not given); nan -> a large
        residual (a run that gave no value)."""
        sd = np.where(np.isfinite(self.data.sd), self.data.sd, 1.0)
        r = (simulated - self.data.values) / sd
        return np.where(np.isfinite(r), r, 1e6).ravel()


def _value(row: dict[str, Any], metric: str) -> float:
    value = row.get(metric)
    return math.nan if row.get("status") != "ok" or value is None else float(value)


@dataclass(frozen=True)
class Fit:
    """A calibration's result (fit.json)."""

    method: str
    keys: list[str]
    values: list[float]
    standard_errors: list[float]
    intervals: list[tuple[float, float]]
    residuals: list[list[float]]
    rss: float
    noise: float | list[float] | None
    """Without sd columns, the data's noise: the least-squares estimate s, or (surrogate) the
    posterior median of each metric's σ; None when every value has its sd."""
    evaluations: int
    runs: int
    band: list[list[list[float]]]
    """Per data row and metric, the 95 % band of the simulated value (linearised, or the
    posterior's 2.5-97.5 % of the runs at the sampled points)."""
    samples: list[list[float]] | None = None

    def as_dict(self) -> dict[str, Any]:
        """Plain data for JSON."""
        return {k: v for k, v in self.__dict__.items() if k != "samples"}


def least_squares(model: Model, x0: np.ndarray, step: float = 1e-3) -> Fit:
    """The least-squares fit (module doc); ``step`` is the forward difference's step as a
    fraction of each key's range."""
    lo = np.array([f.low for f in model.fits])
    hi = np.array([f.high for f in model.fits])
    h = step * (hi - lo)
    sd = np.where(np.isfinite(model.data.sd), model.data.sd, 1.0).ravel()
    evaluations = 0

    def fun(theta: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += 1
        return model.residuals(model.evaluate(theta[None, :])[0])

    def jac(theta: np.ndarray) -> np.ndarray:
        steps = np.where(theta + h <= hi, h, -h)
        shifted = theta + np.diag(steps)
        sims = model.evaluate(np.vstack([theta[None, :], shifted]))
        r0 = model.residuals(sims[0])
        return np.column_stack(
            [(model.residuals(sims[j + 1]) - r0) / steps[j] for j in range(theta.size)]
        )

    result = optimize.least_squares(
        fun, x0, jac=jac, bounds=(lo, hi), method="trf", x_scale=hi - lo
    )
    r, j = fun(result.x), jac(result.x)
    n, p = r.size, result.x.size
    dof = max(n - p, 1)
    rss = float(r @ r)
    noise = None if model.data.weighted else math.sqrt(rss / dof)
    scale = 1.0 if model.data.weighted else rss / dof
    cov = scale * np.linalg.pinv(j.T @ j)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    draws = np.random.default_rng(0).multivariate_normal(
        result.x, cov, size=LINEARISED_DRAWS, check_valid="ignore"
    )
    t = float(stats.t.ppf(0.975, dof))
    sensitivity = j * sd[:, None]  # d(simulated)/dθ
    spread = t * np.sqrt(np.clip(np.einsum("ij,jk,ik->i", sensitivity, cov, sensitivity), 0, None))
    simulated = model.evaluate(result.x[None, :])[0].ravel()
    shape = model.data.values.shape
    return Fit(
        method="least-squares",
        keys=[f.key for f in model.fits],
        values=[float(v) for v in result.x],
        standard_errors=[float(s) for s in se],
        intervals=[(float(v - t * s), float(v + t * s)) for v, s in zip(result.x, se, strict=True)],
        residuals=r.reshape(shape).tolist(),
        rss=rss,
        noise=noise,
        evaluations=evaluations,
        runs=model.runs,
        band=np.stack([simulated - spread, simulated + spread], axis=-1)
        .reshape(*shape, 2)
        .tolist(),
        samples=draws[np.all((draws >= lo) & (draws <= hi), axis=1)].tolist(),
    )


def bayes(
    model: Model, start: Fit, steps: int = 100, walkers: int | None = None, seed: int = 0
) -> Fit:
    """The posterior sample of emcee started around the least-squares fit ``start`` (module
    doc); the first half of the chain is burn-in."""
    import emcee

    lo = np.array([f.low for f in model.fits])
    hi = np.array([f.high for f in model.fits])
    ndim = lo.size
    n_walkers = walkers or max(8, 2 * ndim + 2)
    noise = 1.0 if model.data.weighted else (start.noise or 1.0)

    def log_prob(thetas: np.ndarray) -> np.ndarray:
        inside = np.all((thetas >= lo) & (thetas <= hi), axis=1)
        out = np.full(len(thetas), -np.inf)
        if inside.any():
            sims = model.evaluate(thetas[inside])
            out[inside] = [-0.5 * float(np.sum((model.residuals(s) / noise) ** 2)) for s in sims]
        return out

    rng = np.random.default_rng(seed)
    centre = np.array(start.values)
    spread = np.maximum(np.array(start.standard_errors), 1e-3 * (hi - lo))
    p0 = np.clip(centre + spread * rng.standard_normal((n_walkers, ndim)), lo, hi)
    sampler = emcee.EnsembleSampler(n_walkers, ndim, log_prob, vectorize=True)
    sampler.random_state = np.random.RandomState(seed).get_state()  # emcee's own generator
    sampler.run_mcmc(p0, steps, progress=False)
    chain = sampler.get_chain(discard=steps // 2, flat=True)
    median = np.median(chain, axis=0)
    residuals = model.residuals(model.evaluate(median[None, :])[0])
    predictions = model.evaluate(chain[rng.choice(len(chain), min(200, len(chain)), False)])
    return Fit(
        method="bayes (emcee)",
        keys=start.keys,
        values=[float(v) for v in median],
        standard_errors=[float(s) for s in chain.std(axis=0)],
        intervals=posterior_intervals(chain),
        residuals=residuals.reshape(model.data.values.shape).tolist(),
        rss=float(residuals @ residuals),
        noise=None if model.data.weighted else noise,
        evaluations=steps,
        runs=model.runs,
        band=np.moveaxis(np.nanpercentile(predictions, [2.5, 97.5], axis=0), 0, -1).tolist(),
        samples=chain.tolist(),
    )


def best_case(case: Path, fit: Fit) -> str:
    """The case file's TOML with the fitted values, ready to run."""
    overrides = [f"{k}={toml_value(v)}" for k, v in zip(fit.keys, fit.values, strict=True)]
    data = overridden(read_case_data(case), overrides, case)
    header = "".join(f"# --set {o}\n" for o in overrides)
    return f"# {case}, calibrated ({fit.method}):\n{header}\n" + tomli_w.dumps(
        data, multiline_strings=True
    )


@dataclass(frozen=True)
class Calibration:
    """A finished calibration: the fit, the data it was fitted to and the simulated metrics at
    the fit (data rows × metrics), for the plots (:mod:`perga.studies.calibrate_report`), and
    how many of the fit's runs ran now (the others were found finished)."""

    fit: Fit
    data: Data
    simulated: np.ndarray
    ran: int = 0


POSTERIOR = "posterior.parquet"
"""The posterior sample's file in a calibration's directory (module doc)."""
LINEARISED_DRAWS = 4000
"""Draws of the least-squares posterior (its linearised normal)."""

METHODS = ("least-squares", "bayes", "surrogate", "two-fidelity")
"""The calibration methods (module doc)."""


def calibrate(
    case: Path,
    data_path: Path,
    fits: list[str],
    directory: Path,
    *,
    method: str = "least-squares",
    steps: int = 100,
    runs: int = 100,
    client: Client | None = None,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
    function: Callable[[Job], dict[str, Any]] = run_job,
    progress: Callable[[str], None] | None = None,
) -> Calibration:
    """Fit ``fits`` (``KEY=LO:HI``) of ``case`` to ``data_path``; writes best.toml and fit.json
    (with the provenance: the data file's and the case file's SHA-256, the method, perga's
    version) into ``directory`` and returns the calibration (module doc); ``progress`` is told
    the runs so far and the best vector after each batch."""
    keys = [parse_fit(f) for f in fits]
    for k in keys:
        try:
            split_override(f"{k.key}={k.low}")
        except OverrideError as exc:
            raise StudyError([str(exc)]) from None
    data = load_data(data_path, case, keys)
    directory.mkdir(parents=True, exist_ok=True)
    if method in ("surrogate", "two-fidelity") and runs < minimum_runs(len(keys), len(data.values)):
        need = minimum_runs(len(keys), len(data.values))
        raise StudyError(
            [
                f"--runs {runs}: the {method} method needs at least {need} runs ({len(keys)} "
                f"+ 2 parameter vectors, each a run per data row of {data.path}: "
                f"{len(data.values)})"
            ]
        )
    cheap = None
    if method == "two-fidelity":
        try:
            cheap = analytic_model(
                case, data.conditions, data.metrics, {k.key: k.low for k in keys}
            )
        except NoAnalyticModelError as exc:
            raise StudyError([f"--method two-fidelity: {exc}"]) from None
    rounds: list[Round] = []
    with dask_client(client, scheduler, workers) as c:
        model = Model(case, data, keys, directory, c, function, progress)
        if method in ("surrogate", "two-fidelity"):
            fit, rounds = surrogate_posterior(model, runs, cheap)
        else:
            fit = least_squares(model, np.array([0.5 * (k.low + k.high) for k in keys]))
            if method == "bayes":
                fit = bayes(model, fit, steps=steps)
        simulated = model.evaluate(np.array(fit.values)[None, :])[0]
    (directory / "best.toml").write_text(best_case(case, fit), encoding="utf-8")
    record = fit.as_dict() | {
        "case": str(case),
        "data": str(data_path),
        "metrics": data.metrics,
        "conditions": data.conditions,
        "measured": data.values.tolist(),
        "simulated": simulated.tolist(),
        "interval": "95 %: ±t(0.975, n − p)·se (least squares), posterior 2.5-97.5 % (the others)",
        "rounds": [r.__dict__ for r in rounds],
        "provenance": {
            "data_sha256": hashlib.sha256(Path(data_path).read_bytes()).hexdigest(),
            "case_sha256": hashlib.sha256(Path(case).read_bytes()).hexdigest(),
            "method": method,
            "perga": __version__,
        },
    }
    (directory / "fit.json").write_text(json.dumps(record, indent=2, default=float) + "\n")
    write_posterior(fit, directory / POSTERIOR)
    return Calibration(fit, data, simulated, model.ran)


def write_posterior(fit: Fit, path: Path) -> None:
    """The fit's posterior sample as Parquet, a column per fitted key (SI)."""
    samples = np.asarray(fit.samples if fit.samples else [fit.values], dtype=float)
    pq.write_table(pa.table({k: samples[:, i] for i, k in enumerate(fit.keys)}), path)
