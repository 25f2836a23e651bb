"""``perga window --posterior``: parameter sets drawn from a calibration's posterior, seeds of
their own, the probability that each setting is inside the window. End to end on Dask with a
toy model whose probability is known in closed form, the options' limits on both sides, and
the report, map and tables it writes."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from scipy.stats import norm

from perga.cli import main
from perga.studies.jobs import Job, derived_seed
from perga.studies.study_file import StudyError
from perga.studies.window import foundations, window_study
from perga.studies.window_odds import assumed_values, odds_jobs, read_posterior, run_odds
from perga.studies.window_odds_report import odds_report, write_odds_map, write_odds_table

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "bee-bread-separator.toml"
KEY = "materials.beebread.detachment_energy"
THETA, SIGMA = 0.06, 0.01  # J: the toy posterior N(THETA, SIGMA²)
NOISE = 0.02  # the seeds' sd of both toy metrics
SETS = ["rotor.rpm=1000:1500:3", "hammers.mass=0.05:0.1:2"]


def _release(rpm: float, theta: float) -> float:
    """The toy's expected released fraction: rises with speed, falls with the bond's energy."""
    return 0.5 + 0.4 * (rpm - 1000.0) / 500.0 - 4.0 * (theta - THETA)


def _damage(mass: float) -> float:
    """The toy's expected damaged fraction: rises with the hammer's mass, not with θ."""
    return 0.03 * mass / 0.05


def toy_run(job: Job) -> dict[str, Any]:
    """A run of the toy: the metrics from their closed forms plus the seed's noise."""
    p = job.parameters
    rng = np.random.default_rng(job.seed)
    metrics = {
        "released_fraction": _release(p["rotor.rpm"], p[KEY]) + NOISE * rng.standard_normal(),
        "damaged_fraction": _damage(p["hammers.mass"]) + NOISE * rng.standard_normal(),
        "throughput": 1e-3 * p["rotor.rpm"] / 1000.0,
        "energy_per_kg": 1e3,
        "ledger_closure": 0.0,
    }
    return {"key": job.key, **p, "replicate": job.replicate, "seed": job.seed, **metrics,
            "status": "ok", "reason": "", "notes": "", "wall_time": 0.0,
            "directory": job.directory}  # fmt: skip


def _posterior(path: Path, rows: int = 5000) -> Path:
    theta = THETA + SIGMA * np.random.default_rng(1).standard_normal(rows)
    pq.write_table(pa.table({KEY: theta}), path)
    return path


def _by_hand(rpm: float, mass: float, draws: np.ndarray, seeds: int) -> float:
    """The share of draws inside, from the toy's formulas and the seeds the study gives draw d,
    seed s (replicate d·S + s of seed 0), without the study."""
    inside = 0
    for d, (theta,) in enumerate(draws):
        release, damage = [], []
        for s in range(seeds):
            rng = np.random.default_rng(derived_seed(0, d * seeds + s))
            release.append(_release(rpm, theta) + NOISE * rng.standard_normal())
            damage.append(_damage(mass) + NOISE * rng.standard_normal())
        inside += np.mean(release) >= 0.9 and np.mean(damage) <= 0.05
    return inside / len(draws)


def test_probability_map_of_a_toy_is_its_closed_form(tmp_path: Path) -> None:
    """D = 40 draws × S = 2 seeds at 3 × 2 settings (480 runs on a Dask worker): each setting's
    probability is exactly the share of draws inside computed by hand from the toy's formulas
    and seeds, and within 4 binomial standard errors of the closed form: each draw's seed-mean
    release is normal with variance 16σ² + s²/S and its damage with s²/S, independent, so
    P = Φ((μ_r − 0.9)/√(16σ² + s²/2))·Φ((0.05 − μ_d)/(s/√2)) (the estimator against the
    closed form at 4,000 draws: tests/studies/test_window_posterior.py). The best setting is
    the one of the highest closed-form P; the seed part of the variance is the mean of each
    draw's two seeds' variance, by hand (1e-12)."""
    window = window_study(CASE, SETS, replicates=2, release_target=0.9, damage_limit=0.05)
    posterior = read_posterior(_posterior(tmp_path / "posterior.parquet"), 40, 0)
    result = run_odds(window, posterior, 2, tmp_path / "odds", workers=1, function=toy_run)
    assert len(result.odds) == 6 and result.failed == 0
    noise = [
        [NOISE * np.random.default_rng(derived_seed(0, 2 * d + s)).standard_normal()
         for s in range(2)] for d in range(40)
    ]  # fmt: skip
    seed_part = float(np.mean(np.var(noise, axis=1, ddof=1)))
    expected = {}
    for o in result.odds:
        assert o.probability == _by_hand(o.x, o.y, posterior.draws, 2)
        spread = math.sqrt(16 * SIGMA**2 + NOISE**2 / 2)
        p = norm.cdf((_release(o.x, THETA) - 0.9) / spread) * norm.cdf(
            (0.05 - _damage(o.y)) / (NOISE / math.sqrt(2))
        )
        expected[(o.x, o.y)] = p
        se = math.sqrt(max(p * (1 - p), 0.25 / 40) / 40)
        assert abs(o.probability - p) <= 4 * se, (o.x, o.y, o.probability, p)
        assert o.split["released_fraction"].seed == pytest.approx(seed_part, rel=1e-12)
    assert result.best is not None
    assert (result.best.x, result.best.y) == max(expected, key=lambda k: expected[k])
    write_odds_table(result, tmp_path / "odds")
    table = pq.read_table(tmp_path / "odds" / "odds.parquet").to_pydict()
    assert table["probability"] == [o.probability for o in result.odds]
    assert (tmp_path / "odds" / "odds.csv").read_text().startswith('"rotor.rpm","hammers.mass"')
    assert write_odds_map(result, tmp_path / "odds").stat().st_size > 10_000
    text = odds_report(result, assumed_values(window, posterior.keys), foundations(window, True))
    assert "contact duration 0.1 ms" in text and "detachment_energy = 0.06 J" in text
    assert f"calibrated (drawn from the posterior): `{KEY}`" in text
    assert "materials.beebread.density = 1350.0" in text and KEY + " =" not in text
    best = result.best
    assert f"rotor speed [rpm] = {best.x:.4g}, hammer mass [g] = {best.y * 1e3:.4g}" in text


def test_options_are_checked_on_both_sides(tmp_path: Path) -> None:
    """Two draws and two seeds per draw are accepted, one of either refused (no variance to
    split); a fitted key that is an axis is refused; a missing file is named."""
    path = _posterior(tmp_path / "posterior.parquet", 10)
    window = window_study(CASE, SETS, replicates=2)
    assert len(read_posterior(path, 2, 0).draws) == 2
    with pytest.raises(StudyError, match="--draws"):
        read_posterior(path, 1, 0)
    posterior = read_posterior(path, 2, 0)
    assert len(odds_jobs(window, posterior, 2, tmp_path)) == 6 * 2 * 2
    with pytest.raises(StudyError, match="seeds per parameter set"):
        odds_jobs(window, posterior, 1, tmp_path)
    clash = pq.write_table(pa.table({"rotor.rpm": [1000.0, 1100.0]}), tmp_path / "rpm.parquet")
    assert clash is None
    with pytest.raises(StudyError, match="an axis of the window"):
        odds_jobs(window, read_posterior(tmp_path / "rpm.parquet", 2, 0), 2, tmp_path)


def test_cli_names_a_missing_posterior(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """``--posterior`` of a folder without a posterior sample: exit 2, the file named."""
    code = main(["window", str(CASE), *[f"--set={s}" for s in SETS], "--posterior",
                 str(tmp_path), "-o", str(tmp_path / "w")])  # fmt: skip
    assert code == 2
    assert f"{tmp_path}/posterior.parquet" in capsys.readouterr().err
