"""A run directory names its case from where it stands, never by an absolute path of the
machine: moved (or shared) with the case beside it at the same place, it resumes, reports and
finds its case's folder (relative geometry files start there)."""

from __future__ import annotations

import json
import shutil
import signal
from pathlib import Path

import pytest

from perga.case import load_case
from perga.cli import main
from perga.run.directory import prepare_directory
from perga.run.loop import run_case
from perga.stats.tables import load_run
from perga.stopping import StopSignal

ROOT = Path(__file__).resolve().parents[1]


def _stop(time: float, duration: float, steps: int) -> None:
    """A progress report that stops the run, as SIGTERM would (after the checkpoint at 0)."""
    raise StopSignal(signal.SIGTERM)


def test_a_moved_run_resumes_and_reports_without_an_absolute_path(tmp_path: Path) -> None:
    """single-granule for 0.03 s, stopped at its first progress report, then moved two folders
    deeper: its case named from the run directory before and after (the resumed run names it
    from where it now stands), the resumed run complete, its report written, and the machine's
    absolute path (tmp_path) in none of summary.json, report.md, report.html."""
    case = tmp_path / "cases" / "granule.toml"
    case.parent.mkdir()
    shutil.copyfile(ROOT / "cases" / "single-granule.toml", case)
    first, moved = tmp_path / "runs" / "g", tmp_path / "shared" / "deeper" / "g"
    prepare_directory(first, overwrite=False)
    with pytest.raises(StopSignal):
        run_case(load_case(case, overrides=["solver.duration=0.03"]), case, first, _stop)
    summary = json.loads((first / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "interrupted" and summary["case"] == "../../cases/granule.toml"
    moved.parent.mkdir(parents=True)
    shutil.move(first, moved)
    assert main(["run", "--resume", str(moved), "--quiet"]) == 0
    assert main(["report", str(moved)]) == 0
    text = (moved / "summary.json").read_text(encoding="utf-8")
    summary = json.loads(text)
    assert summary["status"] == "completed" and summary["resumed"] == [0.0]
    assert summary["case"] == "../../../cases/granule.toml"
    assert load_run(moved).case.source_dir.resolve() == case.parent.resolve()
    report = moved / "report" / "report.md"
    assert "Case: `../../../cases/granule.toml` (from the run directory)" in report.read_text()
    for written in (text, report.read_text(), report.with_suffix(".html").read_text()):
        assert str(tmp_path) not in written and str(tmp_path.resolve()) not in written
