"""``perga window`` (the dense grid, ``--posterior`` and ``--adaptive``) stopped midway (SIGINT,
or SIGKILL of the command's process) and run again in the same folder: it runs no finished run
again, loses none, and ends with the map of an uninterrupted study (the adaptive search the
same rounds: each batch is chosen from the runs' values, which a finished run gives back as it
gave them). The runs are a stand-in's (:mod:`tests.studies.study_resume`)."""

from __future__ import annotations

import signal
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from tests.studies.study_resume import (
    check_resumed,
    same_table,
    stop_and_resume,
    uninterrupted,  # noqa: F401 (a fixture)
)

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "bee-bread-separator.toml"
KEY = "materials.beebread.detachment_energy"
AXES = ["--set", "rotor.rpm=1000:1500:5", "--set", "hammers.mass=0.05:0.1:3"]
KINDS = {
    "dense": (["--replicates", "2"], ("window.parquet",)),
    "posterior": (["--draws", "3", "--replicates", "2"], ("odds.parquet",)),
    "adaptive": (["--adaptive", "24"], ("adaptive.parquet", "adaptive-runs.parquet")),
}
"""Each kind of study: its options and the tables that must equal the uninterrupted study's."""


def _args(kind: str, out: Path, posterior: Path) -> list[str]:
    extra = [*KINDS[kind][0], *(["--posterior", str(posterior)] if kind == "posterior" else [])]
    return ["window", str(CASE), *AXES, *extra, "-o", str(out)]


@pytest.mark.parametrize(
    ("kind", "signum", "share"),
    [
        pytest.param(
            "adaptive", signal.SIGKILL, 0.5, id="adaptive-SIGKILL", marks=pytest.mark.slow
        ),
        pytest.param("dense", signal.SIGINT, 0.3, id="dense-SIGINT", marks=pytest.mark.slow),
        pytest.param("dense", signal.SIGKILL, 0.3, id="dense-SIGKILL", marks=pytest.mark.slow),
        pytest.param(
            "posterior", signal.SIGINT, 0.3, id="posterior-SIGINT", marks=pytest.mark.slow
        ),
        pytest.param(
            "posterior", signal.SIGKILL, 0.3, id="posterior-SIGKILL", marks=pytest.mark.slow
        ),
        pytest.param("adaptive", signal.SIGINT, 0.5, id="adaptive-SIGINT", marks=pytest.mark.slow),
    ],
)
def test_a_stopped_window_resumes_to_the_uninterrupted_map(
    kind: str,
    signum: int,
    share: float,
    tmp_path: Path,
    uninterrupted,  # noqa: F811
) -> None:
    """Every kind of window study, stopped by SIGINT or SIGKILL once ``share`` of its runs have
    finished, then run again: no finished run run again or lost, the same table(s) as an
    uninterrupted study's, and the same rows but for each run's directory (its folder's)."""
    posterior = tmp_path / "posterior.parquet"
    theta = 0.06 + 0.01 * np.random.default_rng(1).standard_normal(500)
    pq.write_table(pa.table({KEY: theta}), posterior)
    reference, out = tmp_path / "reference", tmp_path / "window"
    uninterrupted(_args(kind, reference, posterior))
    total = len(list((reference / "runs").glob("*/row.json")))
    resumed = stop_and_resume(_args(kind, out, posterior), out, signum, max(2, int(share * total)))
    check_resumed(resumed, signum, reference)
    assert f"({len(resumed.second)} run now" in resumed.out, resumed.out
    for name in KINDS[kind][1]:
        same_table(out / name, reference / name, drop=("directory",))
    if kind != "adaptive":
        same_table(out / "results.parquet", reference / "results.parquet", drop=("directory",))
