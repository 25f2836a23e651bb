"""A study's run key (perga.studies.jobs.run_key) names the run's whole input: the case file's
data and the geometry files it points to. An edit of either between two sweeps makes the second
run again; a sweep of unchanged files reuses every run."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from distributed import Client

from perga.studies.jobs import run_key
from perga.studies.study_file import Parameter, Study
from perga.studies.sweep import sweep
from tests.case_text import case_text

ROOT = Path(__file__).resolve().parents[2]
SVG = "rounded_hammer.svg"
LONGER = ("M -15 25", "M -20 25")
"""An edit of the hammer's outline: its back end 5 mm further from the hinge (its mass and
moment change)."""


def _case(folder: Path) -> Path:
    """The bundled geometry-hammers case with its hammer outline beside it in ``folder``."""
    shutil.copyfile(ROOT / "geometry" / SVG, folder / SVG)
    text = case_text(ROOT / "cases" / "geometry-hammers.toml")
    path = folder / "case.toml"
    path.write_text(text.replace(f"../geometry/{SVG}", SVG), encoding="utf-8")
    return path


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    assert old in text
    path.write_text(text.replace(old, new), encoding="utf-8")


@pytest.mark.parametrize(
    ("name", "edit"), [(SVG, LONGER), ("case.toml", ("rpm = 400.0", "rpm = 410.0"))]
)
def test_the_key_changes_with_the_case_and_its_geometry_file(
    tmp_path: Path, name: str, edit: tuple[str, str]
) -> None:
    """The same files give the same key; an edit of the case or of the hammer's outline file
    another; undone, the first again."""
    case = _case(tmp_path)
    key = run_key(case, ("solver.duration=0.001",), 7)
    assert run_key(case, ("solver.duration=0.001",), 7) == key
    _edit(tmp_path / name, *edit)
    assert run_key(case, ("solver.duration=0.001",), 7) != key
    _edit(tmp_path / name, *reversed(edit))
    assert run_key(case, ("solver.duration=0.001",), 7) == key


def test_a_sweep_after_an_edit_of_the_geometry_file_runs_again(tmp_path: Path) -> None:
    """Two short runs of 10 granules. Swept again unchanged: both reused. After the hammer's
    outline file is edited: both run again, into new directories."""
    study = Study(
        case=_case(tmp_path),
        parameters={
            "solver.duration": Parameter(values=[4e-4, 8e-4]),
            "granules.count": Parameter(values=[10]),
        },
        metrics=["first_impact_restitution"],
    )
    out = tmp_path / "study"
    with Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=":0") as c:
        first = sweep(study, out, client=c)
        same = sweep(study, out, client=c)
        _edit(tmp_path / SVG, *LONGER)
        edited = sweep(study, out, client=c)
    assert (first.ran, first.failed) == (2, 0)
    assert (same.ran, same.reused) == (0, 2)
    assert (edited.ran, edited.reused, edited.failed) == (2, 0, 0)
    assert {r["key"] for r in edited.rows}.isdisjoint(r["key"] for r in first.rows)
