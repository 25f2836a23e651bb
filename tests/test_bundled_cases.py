"""Every bundled case run by a test (issue 18, item 1). In the default suite each scene runs
for its first 0.02 s (or its whole duration when shorter) twice: both runs complete, their
energy ledger closes within the project's 1 % (and the case's own tolerance, which the run
judged), every table is complete and finite, the two runs write the same bytes, `perga compare`
finds every row that compares the same physics in agreement (exit 0), and `perga render` works
on them (the picture shows the granules). The slow suite runs each in full with the same checks
on ledger and tables, and `perga compare` finds every same-physics row in agreement but the
known misses, each at its measured value. A case that does not record its energy
ledger, granules or hammers gets them added (the ledger is the physics' check, not an output
choice; `perga render` draws from the granule and hammer tables and refuses a run without
them, tests/output/test_render.py)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from perga.case import load_case
from perga.cli import main
from perga.output.render import render
from perga.stats.tables import load_run
from tests.run_files import assert_same_outputs, assert_same_summaries

ROOT = Path(__file__).resolve().parents[1]
SCENES = [p for p in sorted((ROOT / "cases").glob("*.toml")) if load_case(p).chamber is not None]
SHORT = 0.02
"""s: the default suite's share of each case."""
PROMISE = 0.01
"""The project's energy-ledger tolerance: a run's residual within 1 % of the energy in play."""
AGREEING = {
    "four-impacts": 6,
    "paper-decaying-branch": 3,
    "rebound-test": 2,
    "successive-impacts": 6,
    "two-body-impact": 4,
}
"""`perga compare`'s same-physics rows of each case's short run (none for the others): each
must agree."""
KNOWN_MISSES = {
    "separator": {
        r"share of \d+ isolated impacts whose velocity after is within 1 %": (0.968, 0.002),
    },
    "stepped-hammers": {
        r"share of \d+ slides on a face turning with the rotor whose velocity at the end is "
        r"within 1 %": (2 / 12, 1e-9),
    },
}
"""Same-physics rows of a full run known to miss 1 %, by case and quantity: (measured value,
its tolerance). The separator's isolated impacts: 96.8 % within 1 % of the impact law at the
bundled step; the misses are slow impacts near the hinge, where the hammer's point gains its
centripetal speed within the step, the rigid step's first-order error. The stepped hammers'
slides: 2 of 12 within 1 % of the disc on a flat face (median error 7.3e-2), measured, its cause
not yet established."""


def _run(case: Path, out: Path, duration: float | None) -> dict:
    """Run ``case`` (for ``duration`` s, or as bundled) into ``out``; its summary."""
    record = list(load_case(case).output.record)
    sets = [] if duration is None else [f"solver.duration={duration!r}"]
    missing = [t for t in ("granules", "hammers", "energy") if t not in record]
    if missing:
        sets.append(f"output.record={json.dumps(record + missing)}")
    args = ["run", str(case), "-o", str(out), "--quiet", *(a for s in sets for a in ("--set", s))]
    assert main(args) == 0
    return json.loads((out / "summary.json").read_text())


def _check_ledger_and_tables(run: Path, summary: dict) -> None:
    """Completed with its ledger within the promise; every table finite, and the frames of the
    granule, hammer and energy tables the same, from 0 to the run's end."""
    assert summary["status"] == "completed"
    energy = summary["energy"]
    assert abs(energy["closure"]) <= PROMISE, energy
    # closure = residual / energy_in_play: one division and one product, rounding (1e-12)
    assert energy["residual"] == pytest.approx(
        energy["closure"] * energy["energy_in_play"], rel=1e-12, abs=1e-300
    )
    tables = load_run(run)
    for name in ("granules", "hammers", "impacts", "energy"):
        for column, values in getattr(tables, name).items():
            assert np.all(np.isfinite(values)), (name, column)
    frames = tables.energy["time"]
    assert frames[0] == 0.0
    assert frames[-1] == pytest.approx(summary["simulated_time"], rel=1e-12)
    assert np.array_equal(np.unique(tables.granules["time"]), frames)
    assert np.array_equal(np.unique(tables.hammers["time"]), frames)
    for other in sorted(set(run.glob("*.csv")) - {run / f"{n}.csv" for n in ("granules",
                        "hammers", "impacts", "energy")}):  # fmt: skip
        header, *rows = other.read_text().splitlines()
        values = [[float(x) for x in row.split(",")] for row in rows]
        assert all(len(row) == header.count(",") + 1 for row in values), other.name
        assert np.all(np.isfinite(values)), other.name


def _coloured_pixels(png: Path) -> int:
    """Pixels of clear colour: granules (coloured by speed) when the colour bar is off; the
    chamber, rotor and hammers are grey."""
    rgb = mpimg.imread(png)[..., :3]
    return int(np.sum(rgb.max(axis=2) - rgb.min(axis=2) > 0.3))


@pytest.mark.parametrize("case", SCENES, ids=lambda p: p.stem)
def test_a_short_run_of_every_bundled_case(case: Path, tmp_path: Path, capsys) -> None:
    duration = min(SHORT, load_case(case).solver.duration)
    runs = [tmp_path / "a", tmp_path / "b"]
    summaries = [_run(case, run, duration) for run in runs]
    _check_ledger_and_tables(runs[0], summaries[0])
    assert_same_outputs(runs[1], runs[0])
    assert_same_summaries(runs[1], runs[0])
    status, data = _compare(runs[0], tmp_path / "report")
    assert "Traceback" not in capsys.readouterr().err
    said = {r["run"] for r in data["rows"]} | {u["run"] for u in data["unavailable"]}
    assert runs[0].name in said, "compare said nothing about the run"
    assert all(u["reason"] for u in data["unavailable"])
    same_physics = [r for r in data["rows"] if r["tolerance"] is not None]
    assert len(same_physics) >= AGREEING.get(case.stem, 0)
    assert [r["quantity"] for r in same_physics if not r["agrees"]] == []
    assert status == 0
    picture = tmp_path / "frame.png"
    render(runs[0], picture, colorbar=False)
    # measured 7 (one small granule, paper-decaying-branch) to 49 per granule
    assert _coloured_pixels(picture) >= 5 * summaries[0]["granules"]


@pytest.mark.slow
@pytest.mark.parametrize("case", SCENES, ids=lambda p: p.stem)
def test_every_bundled_case_in_full(case: Path, tmp_path: Path) -> None:
    """Ledger and tables as the short runs'; `perga compare`: every same-physics row agrees but
    the case's known misses, each at its measured value, and the exit says whether one
    missed."""
    summary = _run(case, tmp_path / "run", None)
    _check_ledger_and_tables(tmp_path / "run", summary)
    status, data = _compare(tmp_path / "run", tmp_path / "report")
    known = KNOWN_MISSES.get(case.stem, {})
    misses = [r for r in data["rows"] if r["agrees"] is False]
    for row in misses:
        pattern = next((p for p in known if re.fullmatch(p, row["quantity"])), None)
        assert pattern is not None, (row["quantity"], row["simulated"], row["analytic"])
        value, tolerance = known[pattern]
        assert row["simulated"] == pytest.approx(value, abs=tolerance), row["quantity"]
    assert len(misses) == len(known)
    assert status == (1 if known else 0)


def _compare(run: Path, report: Path) -> tuple[int, dict]:
    """`perga compare` of ``run`` into ``report``: its exit status and report.json (strict)."""
    status = main(["compare", str(run), "-o", str(report)])
    data = json.loads(
        (report / "report.json").read_text(), parse_constant=lambda c: pytest.fail(f"JSON has {c}")
    )
    return status, data
