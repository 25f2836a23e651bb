"""The posterior at DEM prices (perga.studies.surrogate) and the analytical model as its cheap
level (perga.studies.analytic_metrics): the GP's predictions against scikit-learn's, the analytic
rebound against DEM shots, the surrogate's posterior against the exact one of a model cheap
enough to sample directly, within 100 runs; bad requests refused (exit 2)."""

from __future__ import annotations

import csv
import functools
import math
from pathlib import Path

import numpy as np
import pytest

from perga.cli import main
from perga.studies.analytic_metrics import AnalyticModel, analytic_model
from perga.studies.calibrate import calibrate, load_data, parse_fit
from perga.studies.jobs import Job
from perga.studies.surrogate import _log_posterior, fit_gp, minimum_runs
from tests.studies.test_calibrate import CASE, ROOT

E, F = "contacts.granule-hammer.restitution", "contacts.granule-hammer.friction"
FITS = [f"{E}=0.4:0.95", f"{F}=0.05:0.8"]
METRICS = ["shot_restitution", "shot_tangential_restitution_centre", "shot_rebound_angle_centre"]
ANGLES = [0.3, 0.7, 1.0, 1.3]
TRUE = (0.7, 0.25)
SD = np.array([0.01, 0.01, 0.01])


def test_the_gp_predicts_as_scikit_learn() -> None:
    """perga's numpy predictions (mean, and sd with the noise) against scikit-learn's
    GaussianProcessRegressor with the same fitted kernel, to 1e-8 of the values' scale
    (rounding of two Cholesky solves)."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    rng = np.random.default_rng(3)
    x = rng.random((12, 2))
    values = 2.0 + np.sin(3 * x[:, 0]) * x[:, 1] + 0.01 * rng.standard_normal(12)
    gp = fit_gp(x, values, seed=0)
    kernel = ConstantKernel(gp.amplitude, "fixed") * Matern(gp.lengths, "fixed", nu=2.5)
    reference = GaussianProcessRegressor(kernel + WhiteKernel(gp.noise, "fixed"), optimizer=None)
    reference.fit(x, (values - gp.offset) / gp.scale)
    new = rng.random((7, 2))
    mean, sd = gp.predict(new)
    ref_mean, ref_sd = reference.predict(new, return_std=True)
    assert np.allclose(mean, gp.offset + gp.scale * ref_mean, rtol=0, atol=1e-8)
    assert np.allclose(sd, gp.scale * ref_sd, rtol=0, atol=1e-8)
    # at a training point it returns the value to within the fitted noise
    assert np.allclose(gp.predict(x)[0], values, atol=3 * gp.scale * math.sqrt(gp.noise) + 1e-9)


@pytest.mark.parametrize("target", ["hammer", "wall"])
def test_the_analytic_rebound_is_a_dem_shot_s(tmp_path: Path, target: str) -> None:
    """The analytical model's e, β and rebound angles at the centre and the contact point against
    a DEM shot's (metrics of the run's trajectory), 2e-3: the bound the shot metrics keep against
    the impulse law (the contact found up to one 2 µs step deep)."""
    quantities = ("restitution", "tangential_restitution_centre", "tangential_restitution_contact",
                  "rebound_angle_centre", "rebound_angle_contact")  # fmt: skip
    metrics = [f"shot_{q}" for q in quantities]
    rows = [{"granules.placement.angle": a, "granules.placement.target": target} for a in ANGLES]
    pair = "granule-hammer" if target == "hammer" else "beebread-steel"
    model = analytic_model(CASE, rows, metrics, {f"contacts.{pair}.restitution": 0.7,
                                                 f"contacts.{pair}.friction": 0.3})  # fmt: skip
    predicted = model(np.array([0.7, 0.3]))[0]
    from perga.studies.jobs import make_job, run_job

    for row, expected in zip(rows, predicted, strict=True):
        got = run_job(make_job(CASE, row, 0, 0, tuple(metrics), tmp_path))
        assert got["status"] == "ok", got["reason"]
        assert np.allclose([got[m] for m in metrics], expected, atol=2e-3), (row, got, expected)


@functools.cache
def _shot(angle: float) -> AnalyticModel:
    return analytic_model(CASE, [{"granules.placement.angle": angle}], METRICS, {E: 0.5, F: 0.1})


def _law(theta: np.ndarray, angle: float) -> np.ndarray:
    """A stand-in for the simulation: the analytic shot's metrics, its β bent by a smooth
    discrepancy the analytical model does not have (+0.03 sin(4f) cos θ)."""
    values = _shot(angle)(theta)[0, 0]
    values[1] += 0.03 * math.sin(4 * theta[1]) * math.cos(angle)
    return values


def fake_run(job: Job) -> dict:
    """A run of the stand-in (module-level: Dask pickles it)."""
    theta = np.array([job.parameters[E], job.parameters[F]])
    values = _law(theta, job.parameters["granules.placement.angle"])
    return {"key": job.key, "status": "ok", **dict(zip(METRICS, values, strict=True))}


def _data(path: Path) -> Path:
    rng = np.random.default_rng(5)
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["granules.placement.angle", *(c for m in METRICS for c in (m, f"{m}_sd"))])
        for angle in ANGLES:
            values = _law(np.array(TRUE), angle) + SD * rng.standard_normal(3)
            writer.writerow([angle, *(c for v, s in zip(values, SD, strict=True) for c in (v, s))])
    return path


@functools.cache
def _exact(data_path: Path) -> np.ndarray:
    """The stand-in's exact 95 % intervals (keys, 2): emcee on the law itself, 32 walkers,
    1,500 steps, the first 500 burnt."""
    import emcee

    data = load_data(data_path, CASE, [parse_fit(f) for f in FITS])

    def log_prob(theta: np.ndarray) -> float:
        if not (0.4 <= theta[0] <= 0.95 and 0.05 <= theta[1] <= 0.8):
            return -np.inf
        simulated = np.array([_law(theta, a) for a in ANGLES])
        return -0.5 * float(np.sum(((simulated - data.values) / data.sd) ** 2))

    sampler = emcee.EnsembleSampler(32, 2, log_prob)
    start = np.array(TRUE) + 1e-3 * np.random.default_rng(0).standard_normal((32, 2))
    sampler.run_mcmc(start, 1500, progress=False)
    return np.percentile(sampler.get_chain(discard=500, flat=True), [2.5, 97.5], axis=0).T


@pytest.mark.slow
def test_the_posterior_from_few_runs_is_the_exact_one(tmp_path: Path) -> None:
    """Against a stand-in for the simulation cheap enough to sample directly (:func:`_exact`):
    each method's 95 % intervals within 15 % of the exact posterior's width at each end (Monte
    Carlo error of both samples: a few %), each holding the true values, from at most 100
    runs; the two-fidelity one from fewer runs than the surrogate alone."""
    data_path = _data(tmp_path / "data.csv")
    exact = _exact(data_path)
    runs = {}
    for method in ("surrogate", "two-fidelity"):
        fit = calibrate(CASE, data_path, FITS, tmp_path / method, method=method, runs=100,
                        workers=1, function=fake_run).fit  # fmt: skip
        runs[method] = fit.runs
        assert fit.runs <= 100
        for (lo, hi), (x_lo, x_hi), truth in zip(fit.intervals, exact, TRUE, strict=True):
            width = x_hi - x_lo
            assert abs(lo - x_lo) < 0.15 * width, (method, lo, hi, exact)
            assert abs(hi - x_hi) < 0.15 * width, (method, lo, hi, exact)
            assert lo < truth < hi
    assert runs["two-fidelity"] < runs["surrogate"], runs


@pytest.mark.slow
def test_a_surrogate_unsure_widens_the_posterior(tmp_path: Path) -> None:
    """From the fewest runs (3 vectors for 2 keys: a surrogate far from converged) the
    intervals are wider than the exact posterior's and hold the true values: the surrogate's
    own variance enters the likelihood, so too few runs give an honest, wide answer instead
    of a narrow wrong one."""
    data_path = _data(tmp_path / "data.csv")
    exact = _exact(data_path)
    runs = minimum_runs(2, len(ANGLES))
    fit = calibrate(CASE, data_path, FITS, tmp_path / "few", method="surrogate", runs=runs,
                    workers=1, function=fake_run).fit  # fmt: skip
    for (lo, hi), (x_lo, x_hi), truth in zip(fit.intervals, exact, TRUE, strict=True):
        assert lo < truth < hi and hi - lo > x_hi - x_lo, (lo, hi, x_lo, x_hi)


def test_the_noise_of_data_without_sd_is_bounded() -> None:
    """Without sd columns each metric's σ is sampled with p(σ) ∝ 1/σ, proper: −∞ outside 1e-5
    to 1 times the metric's largest measured magnitude (else σ → 0 drifts to −∞ on a surrogate
    with its own variance)."""
    from perga.studies.surrogate import Surrogate

    measured = np.array([[0.5], [-2.0]])
    flat = Surrogate(np.zeros(1), np.ones(1), (2, 1), [None, None])
    log_prob = _log_posterior(flat, measured, np.full((2, 1), math.nan))
    top = math.log(2.0)
    inside = log_prob(np.array([[0.5, top - 1e-9], [0.5, top + math.log(1e-5) + 1e-9]]))
    outside = log_prob(np.array([[0.5, top + 1e-9], [0.5, top + math.log(1e-5) - 1e-9]]))
    assert np.all(np.isfinite(inside)) and np.all(outside == -np.inf)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--method", "surrogate", "--runs", str(minimum_runs(1, 1) - 1)],
         f"--runs {minimum_runs(1, 1) - 1}: the surrogate method needs at least"),
        (["--method", "two-fidelity", "--fit", "granules.placement.speed=2:6"],
         "fitted key granules.placement.speed: the analytical model takes the struck pair's"),
    ],
)  # fmt: skip
def test_bad_requests_exit_2(tmp_path: Path, capsys, extra: list[str], message: str) -> None:
    data = tmp_path / "data.csv"
    data.write_text("granules.placement.angle,shot_restitution\n0.3,0.7\n")
    args = ["calibrate", str(CASE), "--data", str(data), "-o", str(tmp_path / "o"),
            "--fit", FITS[0], *extra]  # fmt: skip
    assert main(args) == 2
    assert message in capsys.readouterr().err


def test_a_metric_without_an_analytic_counterpart_is_refused(tmp_path: Path, capsys) -> None:
    data = tmp_path / "data.csv"
    data.write_text("granules.placement.angle,impact_count\n0.3,1\n")
    args = ["calibrate", str(CASE), "--data", str(data), "-o", str(tmp_path / "o"),
            "--fit", FITS[0], "--method", "two-fidelity"]  # fmt: skip
    assert main(args) == 2
    assert "metric impact_count: no analytical counterpart" in capsys.readouterr().err


def test_the_fewest_runs_are_accepted(tmp_path: Path) -> None:
    """The other side of the runs limit: exactly the minimum runs a posterior (one key, one
    row: a first design of two vectors and the check)."""
    data = tmp_path / "data.csv"
    data.write_text("granules.placement.angle,shot_restitution,shot_restitution_sd\n0.3,0.7,0.01\n")
    need = minimum_runs(1, 1)
    result = calibrate(CASE, data, [FITS[0]], tmp_path / "o", method="surrogate", runs=need,
                       workers=1, function=fake_one)  # fmt: skip
    assert result.fit.runs == need


def fake_one(job: Job) -> dict:
    return {"key": job.key, "status": "ok", "shot_restitution": job.parameters[E]}


def test_the_struck_granule_s_law(tmp_path: Path) -> None:
    """granule_speed_after_impact:1 of one granule at rest struck by a hinged plate hammer:
    (1 + e)·M/(M + m)·ωρ with M = I_A/d², I_A of the plate about its hole (parallel axes, by
    hand here), d = ρ − hinge radius; the DEM's within 1 % (0.6 % measured: the frame after the
    impact comes 0.2 ms later, floor friction and the hammer's swing meanwhile)."""
    from perga.studies.jobs import make_job, run_job

    case = ROOT / "cases" / "single-granule.toml"
    model = analytic_model(case, [{"rotor.rpm": 600.0}], ["granule_speed_after_impact:1"],
                           {E: 0.5})  # fmt: skip
    mass, length, width, offset = 0.02826, 0.06, 0.02, 0.005
    inertia = mass * (length**2 + width**2) / 12 + mass * (length / 2 - offset) ** 2
    rho, hinge, m = 0.11, 0.08, 0.00016
    hammer = inertia / (rho - hinge) ** 2
    omega = 600.0 * 2 * math.pi / 60
    expected = 1.7 * hammer / (hammer + m) * omega * rho
    assert model(np.array([0.7]))[0, 0, 0] == pytest.approx(expected, rel=1e-12)
    job = make_job(case, {"solver.duration": 0.03}, 0, 0, ("granule_speed_after_impact:1",),
                   tmp_path)  # fmt: skip
    assert run_job(job)["granule_speed_after_impact:1"] == pytest.approx(expected, rel=0.01)


def test_the_struck_law_needs_its_scene() -> None:
    from perga.studies.analytic_metrics import NoAnalyticModelError

    with pytest.raises(NoAnalyticModelError, match="one granule placed at rest"):
        analytic_model(CASE, [{}], ["granule_speed_after_impact:1"], {E: 0.5})


@pytest.mark.parametrize("low", [0.0, 1.0, 1.5])
def test_a_fitted_key_is_found_from_any_lower_bound(low: float) -> None:
    """Which key is the pair's friction is found by moving it from its lower bound: the move
    must change it whatever the bound (friction in [0, 2]; 1.0 was once moved to itself)."""
    model = analytic_model(CASE, [{}], ["shot_tangential_restitution_centre"], {F: low})
    assert model.scenes[0]["shot"].friction_key == 0
