"""``perga calibrate`` stopped midway (SIGINT, or SIGKILL of the command's process) and run again
in the same folder: it runs no finished run again, loses none, and ends with the fit of an
uninterrupted calibration, for every method (for ``bayes`` the same chain: its seed is fixed, and
every run found finished gives the value the run gave). The runs are a stand-in's
(:mod:`tests.studies.study_resume`); the real runs' resume is the slow test at the end."""

from __future__ import annotations

import csv
import json
import math
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from tests.studies.study_resume import (
    MODELS,
    check_resumed,
    same_table,
    stop_and_resume,
    uninterrupted,  # noqa: F401 (a fixture)
)

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "rebound-test.toml"
TRUE = {"contacts.granule-hammer.restitution": 0.66, "contacts.granule-hammer.friction": 0.35}
SD = {"first_impact_restitution": 0.01, "first_impact_tangential_restitution_contact": 0.02}
FITS = ["contacts.granule-hammer.restitution=0.3:0.95", "contacts.granule-hammer.friction=0.05:0.8"]
ANGLES = (0.3, 1.15, 1.3, 1.4)


def _data(path: Path) -> Path:
    """The stand-in's metrics at TRUE at four angles, each moved by a fixed fraction of its sd."""
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["granules.placement.angle", *(c for m in SD for c in (m, f"{m}_sd"))])
        for k, angle in enumerate(ANGLES):
            cells: list[float] = [angle]
            for j, (m, sd) in enumerate(SD.items()):
                value = MODELS[m]({**TRUE, "granules.placement.angle": angle}, None)
                cells += [value + sd * math.sin(3 * k + j), sd]
            writer.writerow(cells)
    return path


def _args(method: str, data: Path, out: Path) -> list[str]:
    return ["calibrate", str(CASE), "--data", str(data), *(a for f in FITS for a in ("--fit", f)),
            "--method", method, "--steps", "6", "--runs", "32", "-o", str(out)]  # fmt: skip


@pytest.mark.parametrize(
    ("method", "signum", "share"),
    [
        *(
            pytest.param(
                method, signum, share, id=f"{method}-{signum.name}", marks=pytest.mark.slow
            )
            for method, signum, share in (
                ("least-squares", signal.SIGINT, 0.3),
                ("least-squares", signal.SIGKILL, 0.3),
                ("bayes", signal.SIGINT, 0.6),  # stopped in the sampler: its chain goes on
                ("bayes", signal.SIGKILL, 0.6),
                ("surrogate", signal.SIGINT, 0.5),
                ("surrogate", signal.SIGKILL, 0.5),
                ("two-fidelity", signal.SIGINT, 0.5),
                ("two-fidelity", signal.SIGKILL, 0.5),
            )
        ),
    ],
)
def test_a_stopped_calibration_resumes_to_the_uninterrupted_fit(
    method: str,
    signum: int,
    share: float,
    tmp_path: Path,
    uninterrupted,  # noqa: F811
) -> None:
    """Every method, stopped by SIGINT or SIGKILL once ``share`` of its runs have finished, then
    run again: no finished run run again or lost, the same fit.json, best.toml and posterior
    sample as an uninterrupted calibration's."""
    data = _data(tmp_path / "measured.csv")
    reference, out = tmp_path / "reference", tmp_path / "calibration"
    uninterrupted(_args(method, data, reference))
    total = len(list((reference / "runs").glob("*/row.json")))
    resumed = stop_and_resume(_args(method, data, out), out, signum, max(2, int(share * total)))
    check_resumed(resumed, signum, reference)
    assert f"({len(resumed.second)} run now, " in resumed.out, resumed.out
    fit, expected = (json.loads((d / "fit.json").read_text()) for d in (out, reference))
    assert fit == expected
    assert (out / "best.toml").read_text() == (reference / "best.toml").read_text()
    same_table(out / "posterior.parquet", reference / "posterior.parquet")
    assert np.isfinite(fit["values"]).all() and fit["runs"] == total


@pytest.mark.slow
def test_a_real_calibration_stopped_by_sigint_resumes_to_the_same_fit(tmp_path: Path) -> None:
    """The worked example's least-squares fit with real runs (70 runs of the rebound test, about
    10 s on two workers), stopped by SIGINT once a third of its rows are on disk and run again:
    every row found on disk stays the same file (no finished run ran again), and fit.json and
    best.toml equal an uninterrupted calibration's."""
    data = ROOT / "examples" / "calibration" / "measured.csv"

    def command(out: Path) -> list[str]:
        return ["perga", "calibrate", str(CASE), "--data", str(data), "--fit",
                "contacts.granule-hammer.restitution=0.4:0.95", "--workers", "2", "--quiet",
                "-o", str(out)]  # fmt: skip

    reference, out = tmp_path / "reference", tmp_path / "calibration"
    subprocess.run(command(reference), check=True, capture_output=True, timeout=600)
    total = len(list((reference / "runs").glob("*/row.json")))
    proc = subprocess.Popen(command(out), stderr=subprocess.PIPE, text=True)
    end = time.monotonic() + 300
    while len(list((out / "runs").glob("*/row.json"))) < total // 3:
        assert proc.poll() is None and time.monotonic() < end, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    between = {p: (p.stat().st_ino, p.stat().st_mtime_ns) for p in out.glob("runs/*/row.json")}
    assert 0 < len(between) < total
    done = subprocess.run(command(out), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert {p: (p.stat().st_ino, p.stat().st_mtime_ns) for p in between} == between
    assert len(list(out.glob("runs/*/row.json"))) == total
    fit, expected = (json.loads((d / "fit.json").read_text()) for d in (out, reference))
    assert fit["values"] == expected["values"] and fit["rss"] == expected["rss"]
    assert (out / "best.toml").read_text() == (reference / "best.toml").read_text()
