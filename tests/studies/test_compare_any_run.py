"""``perga compare RUN`` says why it could not compute a statistic (issue 15, item 5); that it
works on a run of every bundled case (exit 0 or 1, never a traceback, strict JSON) is in
tests/test_bundled_cases.py."""

import json
from pathlib import Path

import pytest

from perga.case import load_case
from perga.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENES = [p for p in sorted((ROOT / "cases").glob("*.toml")) if load_case(p).chamber is not None]
PARAMETER_SETS = [p for p in sorted((ROOT / "cases").glob("*.toml")) if p not in SCENES]


def test_a_run_that_ends_before_the_first_impact_says_so(tmp_path, capsys):
    """A hinged-hammer run stopped before its first impact: each statistic it cannot give is
    named with the reason (its other side, a run with impacts, is in the test above)."""
    run, report = tmp_path / "run", tmp_path / "report"
    case = ROOT / "cases" / "single-granule.toml"
    short = ["--set", "solver.duration=0.002"]
    assert main(["run", str(case), "-o", str(run), "--quiet", *short]) == 0
    assert main(["compare", str(run), "-o", str(report)]) == 0
    reasons = json.loads((report / "report.json").read_text())["unavailable"]
    assert any("0 granule-hammer impacts completed in the run's 0.002 s" in u["reason"]
               for u in reasons)  # fmt: skip
    assert "Not computed, and why" in (report / "report.md").read_text()


@pytest.mark.parametrize("case", PARAMETER_SETS, ids=lambda p: p.stem)
def test_a_parameter_set_is_refused_by_run_as_bad_input(case, tmp_path, capsys):
    assert main(["run", str(case), "-o", str(tmp_path / "run"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "[chamber] is missing" in err and "Traceback" not in err


def test_free_flight_ends_at_the_first_collision_between_frames(tmp_path):
    """successive-impacts, in full: the granule bounces off the wall between two frames, more
    than 1 mm from it at both; the flight row must stop there (it compared 73 % off before the
    window ended at any change of speed beyond the floor's f g Δt)."""
    run, report = tmp_path / "run", tmp_path / "report"
    case = str(ROOT / "cases" / "successive-impacts.toml")
    assert main(["run", case, "-o", str(run), "--quiet"]) == 0
    assert main(["compare", str(run), "-o", str(report)]) == 0
    rows = json.loads((report / "report.json").read_text())["rows"]
    flight = [r for r in rows if r["quantity"].startswith("r(t) in free flight")]
    assert flight and all(abs(r["error"]) <= 0.01 for r in flight)


def test_one_blade_run_gives_its_exit_speed_and_says_why_there_is_no_map(tmp_path):
    """One blade-exit run past the exit: its row, and Fig. 3 (a map over ω and f) named as not
    drawn with the reason (matplotlib's contour raised TypeError on a 1 × 1 grid)."""
    run, report = tmp_path / "run", tmp_path / "report"
    case = str(ROOT / "cases" / "blade-exit.toml")
    assert main(["run", case, "-o", str(run), "--quiet", "--set", "solver.duration=0.08"]) == 0
    assert main(["compare", str(run), "-o", str(report)]) == 0
    data = json.loads((report / "report.json").read_text())
    agreeing = [r for r in data["rows"] if r["tolerance"] is not None]
    assert len(agreeing) == 1 and agreeing[0]["quantity"].startswith("v_max at ω")
    assert any("1 ω × 1 f" in u["reason"] for u in data["unavailable"])


def test_the_main_run_against_the_impact_law(tmp_path):
    """The README's main case (rigid separator), its first 0.2 s at dt = 1e-5 s: every isolated
    impact's velocity after within 1 % of the law with friction (measured: 343 of 379
    isolated, worst 0.90 %; at the bundled 4e-5 s 96.8 % are, the hammer's acceleration within
    a step being first order in dt), the isolated impacts' loss within 1 % of the law's, the
    ledger's contact term explained, and a verdict in words; no NaN anywhere."""
    run, report = tmp_path / "run", tmp_path / "report"
    sets = ["--set", "solver.duration=0.2", "--set", "solver.dt=1e-5"]
    case = str(ROOT / "cases" / "separator.toml")
    assert main(["run", case, "-o", str(run), "--quiet", *sets]) == 0
    assert main(["compare", str(run), "-o", str(report)]) == 0
    data = json.loads(
        (report / "report.json").read_text(), parse_constant=lambda c: pytest.fail(f"JSON has {c}")
    )
    rows = {r["quantity"].split(" whose")[0]: r for r in data["rows"]}
    share = next(r for q, r in rows.items() if q.startswith("share of"))
    assert share["simulated"] == 1.0 and share["agrees"]
    assert rows["energy lost in the isolated impacts"]["agrees"]
    ledger = next(r for q, r in rows.items() if q.startswith("energy lost in contacts"))
    assert "the other impacts'" in ledger["reason"] and ledger["agrees"] is None
    (impacts,) = data["impacts"]
    assert impacts["isolated"] > 0.8 * impacts["impacts"] > 250
    assert "are isolated; on those the velocity after agrees" in impacts["verdict"]
    stats = impacts["statistics"]
    assert len(stats) == 7  # velocity, spin, restitution, slip, energy lost, given, per granule
    assert stats["energy lost per granule (relative)"]["p99"] < 0.01
    # Newton's law as the solver holds it: exact to rounding in most impacts (median), to
    # 8.2e-4 in the slowest (99th percentile: ten iterations of the contact and the pin)
    assert stats["normal restitution (relative)"]["median"] < 1e-9
    assert stats["normal restitution (relative)"]["p99"] < 2e-3
    assert "Impacts, one by one" in (report / "report.md").read_text()


@pytest.mark.slow
def test_soft_runs_at_two_contact_durations_give_the_order_of_the_fall(tmp_path):
    """The soft separator's first 0.25 s at t_c = 0.1 and 0.05 ms, compared together: one row,
    the order at which the isolated sliding impacts' median error against the instantaneous
    law falls with t_c, first order (measured 0.97: 5.98e-3 → 3.06e-3); the sticking ones do
    not fall (4.2e-2, 3.9e-2), which the row says with its numbers."""
    case = str(ROOT / "cases" / "soft-separator.toml")
    runs = [tmp_path / "full", tmp_path / "half"]
    for run, t_c in zip(runs, (1e-4, 5e-5), strict=True):
        sets = ["--set", "solver.duration=0.25", "--set", f"contact_model.duration={t_c}"]
        assert main(["run", case, "-o", str(run), "--quiet", *sets]) == 0
    report = tmp_path / "report"
    assert main(["compare", *map(str, runs), "-o", str(report)]) == 0
    data = json.loads((report / "report.json").read_text())
    (row,) = [r for r in data["rows"] if r["quantity"].startswith("order of the sliding")]
    assert row["run"] == "full / half" and row["agrees"] is None
    assert 0.7 < row["simulated"] < 1.3
    assert "which do not fall" in row["reason"]
