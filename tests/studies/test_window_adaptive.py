"""``perga window --adaptive``: the adaptive search run as study runs on Dask. On a toy whose
boundary is known (release rises across a line in speed, damage across one in mass) it finds
the window within its budget, its k-th run at a setting is the dense study's replicate k (a
second search in the folder runs nothing), and it writes its table, map and report."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest

from perga.cli import main
from perga.studies.jobs import ROW, Job, derived_seed
from perga.studies.sweep import jobs_of
from perga.studies.window import window_study
from perga.studies.window_adaptive import run_adaptive
from perga.studies.window_adaptive_report import write_adaptive

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "bee-bread-separator.toml"
SETS = ["rotor.rpm=400:1600:7", "hammers.mass=0.025:0.1:7"]


def toy_run(job: Job) -> dict[str, Any]:
    """Release 0.5 + (rpm − 800)/400 and damage 0.02 + (mass − 0.0625)·2 (both clipped to
    [0, 1]) plus seed noise of sd 0.02: inside for rpm ≥ 960 and mass ≤ 0.0775 kg."""
    p = job.parameters
    rng = np.random.default_rng(job.seed)
    release = np.clip(0.5 + (p["rotor.rpm"] - 800.0) / 400.0, 0, 1) + 0.02 * rng.normal()
    damage = np.clip(0.02 + (p["hammers.mass"] - 0.0625) * 2.0, 0, 1) + 0.02 * rng.normal()
    row = {"key": job.key, **p, "replicate": job.replicate, "seed": job.seed,
           "released_fraction": float(release), "damaged_fraction": float(damage),
           "throughput": 0.01, "energy_per_kg": 1e3, "ledger_closure": 0.0, "status": "ok",
           "reason": "", "notes": "", "wall_time": 0.0, "directory": job.directory}  # fmt: skip
    Path(job.directory).mkdir(parents=True, exist_ok=True)
    (Path(job.directory) / ROW).write_text(json.dumps(row))  # found again, as a run's
    return row


def test_adaptive_window_of_a_toy_on_dask(tmp_path: Path) -> None:
    """7 × 7 settings, a budget of 40 runs (the dense grid with 3 replicates: 147): at most 40
    runs; every setting whose P is settled (≤ 0.1 or ≥ 0.9) classified as the noise-free toy
    (the band ±0.02 of noise makes the cells next to the lines unsure, not wrong); each run at a
    setting is replicate k with the dense study's seed k; a second search finds them all."""
    window = window_study(CASE, SETS, replicates=3, release_target=0.9, damage_limit=0.05)
    out = tmp_path / "adaptive"
    out.mkdir()
    (out / "results.parquet").write_bytes(b"a dense study's table")  # kept: not the search's
    result = run_adaptive(window, out, budget=40, workers=1, function=toy_run)
    search = result.search
    assert search.runs <= 40 and len(result.rows) == search.runs == result.ran
    xs, ys = np.meshgrid(search.xs, search.ys)
    truth = (np.clip(0.5 + (xs - 800) / 400, 0, 1) >= 0.9) & (0.02 + (ys - 0.0625) * 2 <= 0.05)
    settled = (search.probability <= 0.1) | (search.probability >= 0.9)
    assert settled.sum() >= 30
    assert np.array_equal(search.inside[settled], truth[settled])
    seen: dict[tuple[float, float], int] = {}
    for row in result.rows:
        k = seen.get((row["rotor.rpm"], row["hammers.mass"]), 0)
        seen[(row["rotor.rpm"], row["hammers.mass"])] = k + 1
        assert row["replicate"] == k and row["seed"] == derived_seed(0, k)
    again = run_adaptive(window, out, budget=40, workers=1, function=toy_run)
    assert again.ran == 0 and again.search.runs == search.runs
    assert (out / "results.parquet").read_bytes() == b"a dense study's table"
    assert pq.read_table(out / "adaptive-runs.parquet").num_rows == search.runs
    write_adaptive(result, out)
    table = pq.read_table(out / "adaptive.parquet").to_pydict()
    assert sum(table["runs"]) == search.runs and len(table["probability"]) == 49
    assert table["inside"] == search.inside.ravel().tolist()
    report = (out / "adaptive.md").read_text()
    assert f"- runs: {search.runs} in {search.rounds} rounds" in report
    assert "detachment_energy = 0.06 J" in report
    assert (out / "adaptive.png").stat().st_size > 10_000


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--adaptive", "5"], "--adaptive: "),
        (["--adaptive", "40", "--posterior", "x"], "give one of them"),
    ],
)
def test_adaptive_refusals(tmp_path: Path, capsys, extra: list[str], message: str) -> None:
    """A budget below the coarse grid's runs, and both --adaptive and --posterior: exit 2 with
    the reason."""
    code = main(["window", str(CASE), *[f"--set={s}" for s in SETS], *extra,
                 "-o", str(tmp_path / "w"), "--workers", "1"])  # fmt: skip
    assert code == 2
    assert message in capsys.readouterr().err


def on_the_lines(job: Job) -> dict[str, Any]:
    """The toy's row with both metrics exactly on their thresholds (release 0.9, damage 0.05) at
    every setting: no run can settle a class (P = 1/4 everywhere)."""
    row = toy_run(job)
    row.update(released_fraction=0.9, damaged_fraction=0.05)
    (Path(job.directory) / ROW).write_text(json.dumps(row))
    return row


def test_repeated_settings_are_the_dense_studys_replicates(tmp_path: Path) -> None:
    """2 × 2 settings whose class no run settles: the search runs them again until its budget
    of 12 is spent (the coarse grid's two runs each, then one more each); the k-th run at a
    setting is replicate k with seed k's, the same run (and key) as the dense study's
    replicate k."""
    sets = ["rotor.rpm=940:980:2", "hammers.mass=0.075:0.08:2"]
    window = window_study(CASE, sets, replicates=3, release_target=0.9, damage_limit=0.05)
    result = run_adaptive(window, tmp_path / "a", budget=12, workers=1, function=on_the_lines)
    assert result.search.runs == 12 and result.search.stopped == "budget"
    seen: dict[tuple[float, float], int] = {}
    for row in result.rows:
        k = seen.get((row["rotor.rpm"], row["hammers.mass"]), 0)
        seen[(row["rotor.rpm"], row["hammers.mass"])] = k + 1
        assert row["replicate"] == k and row["seed"] == derived_seed(0, k)
    assert sorted(seen.values()) == [3, 3, 3, 3] and len({r["key"] for r in result.rows}) == 12
    dense = {job.key for job in jobs_of(window.study, tmp_path / "a")}
    assert {r["key"] for r in result.rows} == dense
