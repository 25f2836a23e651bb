"""``perga run CASE --from RUN[:TIME]`` (issue 15, item 4): a case started from another run's
granules (a settled bed) begins exactly where that run's frame left them; the resting overlap
an explicit placement allows is checked on both sides of its limit; every refusal exits 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from perga.case import CaseError
from perga.cli import main
from perga.model.compile import validated
from perga.output.tables import read_columns

ROOT = Path(__file__).resolve().parents[1]
SEPARATOR = ROOT / "cases" / "separator.toml"
SINGLE = ROOT / "cases" / "single-granule.toml"
COLUMNS = ("id", "x", "y", "vx", "vy", "angular_velocity", "radius")


@pytest.fixture(scope="module")
def settled(tmp_path_factory) -> Path:
    """The rigid separator run for 0.03 s (impacts under way, granules spinning)."""
    out = tmp_path_factory.mktemp("from") / "run"
    args = ["run", str(SEPARATOR), "-o", str(out), "--quiet", "--set", "solver.duration=0.03"]
    assert main(args) == 0
    return out


def frame(run: Path, time: float) -> dict[str, np.ndarray]:
    """The run's last frame at or before ``time`` (s)."""
    table = read_columns(run / "granules.csv")
    rows = table["time"] == table["time"][table["time"] <= time + 1e-9].max()
    return {c: table[c][rows] for c in COLUMNS}


@pytest.mark.parametrize(("at", "taken"), [("", 0.03), (":0.02", 0.02), (":0.0205", 0.02)])
def test_a_run_starts_where_the_other_left_its_granules(settled, tmp_path, at, taken):
    """The new run's frame at t = 0 holds the other run's granules at its last frame at or
    before TIME, bit for bit (positions, velocities, spins, radii), under another rotor speed."""
    out = tmp_path / "new"
    args = ["run", str(SEPARATOR), "-o", str(out), "--quiet", "--from", f"{settled}{at}",
            "--set", "rotor.rpm=900", "--set", "solver.duration=0.001"]  # fmt: skip
    assert main(args) == 0
    start, source = frame(out, 0.0), frame(settled, taken)
    assert np.count_nonzero(source["angular_velocity"]) > 0  # spins are carried, not zeros
    for column in COLUMNS[1:]:
        np.testing.assert_array_equal(start[column], source[column], err_msg=column)


def test_refusals(settled, tmp_path, capsys):
    out = str(tmp_path / "new")
    cases = {
        "no granule table": ["--from", str(tmp_path)],
        "time must be": ["--from", f"{settled}:-1"],
        "the sizes must be the same": ["--from", str(settled), "--set", "granules.radius=0.003"],
        "--resume RUN goes on": ["--from", str(settled), "--resume", str(settled)],
        "overlaps a hammer": ["--from", str(settled), "--set", "hammers.swing_angle=0.5"],
    }
    for problem, extra in cases.items():
        case = [] if "--resume" in extra else [str(SEPARATOR)]
        assert main(["run", *case, "-o", out, "--quiet", *extra]) == 2, problem
        assert problem in capsys.readouterr().err, problem


def placed(positions: list[list[float]], overlap: float) -> list[str]:
    """Overrides that put granules explicitly with a resting ``overlap`` allowed."""
    text = ", ".join(f"[{x!r}, {y!r}]" for x, y in positions)
    return [
        f"granules.count={len(positions)}",
        f'granules.placement={{kind = "explicit", positions = [{text}], overlap = {overlap!r}}}',
    ]


@pytest.mark.parametrize(("allowed", "accepted"), [(0.99e-5, False), (1.01e-5, True)])
def test_a_resting_overlap_is_allowed_up_to_what_the_placement_states(allowed, accepted):
    """Two granules of radius 2.5 mm whose centres are 5 mm − 10 µm apart overlap by 10 µm."""
    overrides = placed([[0.05, 0.0], [0.05 + 0.005 - 1e-5, 0.0]], allowed)
    if accepted:
        validated(SINGLE, overrides=overrides)
    else:
        with pytest.raises(CaseError, match="granules 0 and 1 overlap"):
            validated(SINGLE, overrides=overrides)


@pytest.mark.parametrize(("allowed", "accepted"), [(0.00124, True), (0.00125, False)])
def test_the_allowed_overlap_stays_below_half_the_smallest_radius(allowed, accepted):
    overrides = placed([[0.05, 0.0]], allowed)
    if accepted:
        validated(SINGLE, overrides=overrides)
    else:
        with pytest.raises(CaseError, match="below half the smallest radius"):
            validated(SINGLE, overrides=overrides)
