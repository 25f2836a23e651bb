"""perga calibrate: synthetic rebound data made from known restitution and friction plus noise
are fitted back, the known values inside the reported 95 % intervals; bad data files and fit
ranges exit 2 naming the file and the field."""

from __future__ import annotations

import csv
import hashlib
import json
import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from perga import __version__
from perga.cli import main
from perga.studies.calibrate import Calibration, Data, Fit, calibrate
from perga.studies.calibrate_report import write_plots
from perga.studies.study_file import Parameter, Study
from perga.studies.sweep import sweep
from tests.figure_data import lines, saved_figures

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "rebound-test.toml"
TRUE = {"contacts.granule-hammer.restitution": 0.66, "contacts.granule-hammer.friction": 0.35}
SD = {"first_impact_restitution": 0.01, "first_impact_tangential_restitution_contact": 0.02}
FITS = ["contacts.granule-hammer.restitution=0.3:0.95", "contacts.granule-hammer.friction=0.05:0.8"]


def _synthetic(path: Path, work: Path, seed: int) -> None:
    """Data at six angles from runs at TRUE, plus Gaussian noise of SD (seeded)."""
    parameters = {k: Parameter(values=[v]) for k, v in TRUE.items()}
    parameters["granules.placement.angle"] = Parameter(values=[0.3, 0.7, 1.0, 1.15, 1.3, 1.4])
    result = sweep(Study(case=CASE, parameters=parameters, metrics=list(SD)), work, workers=2)
    rng = np.random.default_rng(seed)
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["granules.placement.angle", *(c for m in SD for c in (m, f"{m}_sd"))])
        for row in result.rows:
            cells = [row["granules.placement.angle"]]
            for m, sd in SD.items():
                cells += [row[m] + rng.normal(0.0, sd), sd]
            writer.writerow(cells)


def test_least_squares_recovers_known_values(tmp_path: Path, monkeypatch) -> None:
    """Restitution and friction together from rebound restitutions: both known values fall in
    the 95 % intervals, which are a few standard errors wide (the fit is not vacuous: a
    noise-free parameter would sit within 1e-3 of its value; here intervals of ~0.01)."""
    data = tmp_path / "measured.csv"
    _synthetic(data, tmp_path / "truth", seed=11)
    out = tmp_path / "fit"
    saved = saved_figures(monkeypatch)
    said: list[str] = []
    result = calibrate(CASE, data, FITS, out, workers=2, progress=said.append)
    write_plots(result, out)
    fit = result.fit
    for key, (lo, hi), value in zip(fit.keys, fit.intervals, fit.values, strict=True):
        assert lo < TRUE[key] < hi, (key, lo, hi)
        assert hi - lo < 0.05 and abs(value - TRUE[key]) < 0.03
    record = json.loads((out / "fit.json").read_text())
    assert record["method"] == "least-squares" and len(record["simulated"]) == 6
    # provenance: what was fitted to what, by which method and perga
    provenance = record["provenance"]
    assert provenance["data_sha256"] == hashlib.sha256(data.read_bytes()).hexdigest()
    assert provenance["case_sha256"] == hashlib.sha256(CASE.read_bytes()).hexdigest()
    assert provenance["method"] == "least-squares" and provenance["perga"] == __version__
    # progress after every batch: the runs so far, growing, and the best vector with its RSS
    runs = [int(line.split()[1]) for line in said]
    assert runs == sorted(runs) and runs[-1] == fit.runs and len(said) >= 3
    assert "best so far contacts.granule-hammer.restitution = " in said[-1]
    best = (out / "best.toml").read_text()
    assert f"restitution = {fit.values[0]!r}" in best
    # the posterior sample perga window --posterior draws from: the linearised normal, within
    # the bounds; its mean and sd those of the fit to 4 standard errors of a 4,000-draw sample
    posterior = pq.read_table(out / "posterior.parquet").to_pydict()
    assert list(posterior) == fit.keys
    for key, value, se in zip(fit.keys, fit.values, fit.standard_errors, strict=True):
        sample = np.array(posterior[key])
        assert 3000 < sample.size <= 4000
        assert abs(sample.mean() - value) < 4 * se / math.sqrt(sample.size)
        assert sample.std() == pytest.approx(se, rel=4 * math.sqrt(0.5 / sample.size))
    # the figures draw the fit's numbers (issue 18, item 6): the measured points, the model at
    # the fit (in the abscissa's order) and each row's residual
    with data.open() as f:
        rows = list(csv.DictReader(f))
    panels = saved["fit.png"].axes
    residuals = saved["residuals.png"].axes[0].get_lines()  # one per metric, then the zero line
    assert len(panels) == len(SD) == len(residuals) - 1
    for j, panel in enumerate(panels):
        metric, unit = panel.get_ylabel().split(" [")  # the metric with its unit: "e [-]"
        assert unit == "-]"
        measured = [float(row[metric]) for row in rows]
        assert sorted(panel.containers[0].lines[0].get_ydata()) == sorted(measured)
        model = lines(panel)["model at the fit"][1]
        assert sorted(model) == sorted(v[j] for v in record["simulated"])
        assert np.array_equal(residuals[j].get_ydata(), np.array(fit.residuals)[:, j])


@pytest.mark.slow
def test_bayes_posterior_covers_known_values(tmp_path: Path) -> None:
    """emcee from the least-squares optimum: the 95 % posterior intervals hold the known values."""
    data = tmp_path / "measured.csv"
    _synthetic(data, tmp_path / "truth", seed=12)
    result = calibrate(CASE, data, FITS, tmp_path / "fit", method="bayes", steps=40, workers=2)
    write_plots(result, tmp_path / "fit")
    fit = result.fit
    for key, (lo, hi) in zip(fit.keys, fit.intervals, strict=True):
        assert lo < TRUE[key] < hi, (key, lo, hi)
    assert (tmp_path / "fit" / "posterior.png").exists()


@pytest.mark.parametrize(
    ("table", "fits", "message"),
    [
        ("rotor.rpmm,first_impact_restitution\n1,0.7\n", FITS, "rotor.rpmm: unknown key"),
        ("granules.placement.angle,bogus_metric\n0.3,0.7\n", FITS, "no metric column"),
        ("granules.placement.angle,first_impact_restitution\n0.3,high\n", FITS,
         "not a finite number"),
        ("granules.placement.angle,first_impact_restitution,first_impact_restitution_sd\n"
         "0.3,0.7,0\n", FITS, "first_impact_restitution_sd: must be a finite number > 0"),
        ("granules.placement.angle,first_impact_restitution\n9,0.7\n", FITS,
         "granules.placement.angle: Input should be less than or equal to 1.5"),
        ("granules.placement.angle,first_impact_restitution\n0.3,0.7\n",
         ["contacts.granule-hammer.restitution=0.9:0.9"], "the range needs LO < HI"),
        ("granules.placement.angle,first_impact_restitution\n0.3,0.7\n",
         ["contacts.granule-hammer.restitution=0.95:0.3"], "the range needs LO < HI"),
        ("granules.placement.angle,first_impact_restitution\n0.3,0.7\n",
         ["restitution"], "expected KEY=LO:HI"),
    ],
)  # fmt: skip
def test_bad_data_and_fits_exit_2(tmp_path: Path, capsys, table: str, fits, message: str) -> None:
    data = tmp_path / "data.csv"
    data.write_text(table)
    args = ["calibrate", str(CASE), "--data", str(data), "-o", str(tmp_path / "o")]
    for f in fits:
        args += ["--fit", f]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert message in err, err


def test_the_command_writes_the_plots_of_the_calibration(tmp_path: Path, monkeypatch) -> None:
    """``perga calibrate`` hands the study's result to the report (the study writes best.toml
    and fit.json only): fit.png draws the measured values and the model at the fit,
    residuals.png the residuals, each exactly."""
    key = "contacts.granule-hammer.restitution"
    angles = [0.3, 0.7, 1.0]
    data = Data(
        tmp_path / "measured.csv",
        [{"granules.placement.angle": a} for a in angles],
        ["first_impact_restitution"],
        np.array([[0.60], [0.62], [0.65]]),
        np.full((3, 1), 0.01),
    )
    fit = Fit(
        "least-squares", [key], [0.66], [0.01], [(0.64, 0.68)], [[1.0], [-2.0], [3.0]], 14.0,
        None, 3, 9, [[[0.59, 0.63]], [[0.60, 0.64]], [[0.64, 0.68]]],
    )  # fmt: skip
    simulated = np.array([[0.61], [0.60], [0.68]])

    def study(case: Path, data_path: Path, fits: list[str], directory: Path, **_) -> Calibration:
        directory.mkdir(parents=True)
        return Calibration(fit, data, simulated)

    monkeypatch.setattr("perga.studies.calibrate.calibrate", study)
    saved = saved_figures(monkeypatch)
    out = tmp_path / "out"
    args = ["calibrate", str(CASE), "--data", str(data.path), "--fit", f"{key}=0.3:0.95"]
    assert main([*args, "-o", str(out)]) == 0
    assert set(saved) == {"fit.png", "residuals.png"}
    assert (out / "fit.png").is_file() and (out / "residuals.png").is_file()
    panel = saved["fit.png"].axes[0]
    assert list(panel.containers[0].lines[0].get_ydata()) == [0.60, 0.62, 0.65]
    assert list(lines(panel)["model at the fit"][1]) == [0.61, 0.60, 0.68]
    assert list(saved["residuals.png"].axes[0].get_lines()[0].get_ydata()) == [1.0, -2.0, 3.0]
