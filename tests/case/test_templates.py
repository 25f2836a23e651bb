"""perga new: every template is written with its geometry beside it into an empty folder, and
runs from there; refusals name what is in the way."""

import json

import pytest

from perga.case.templates import CASES, TEMPLATES
from perga.cli import main


@pytest.mark.parametrize("name", sorted(TEMPLATES))
def test_a_new_case_runs_from_an_empty_folder(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["new", name, "-o", "x.toml"]) == 0
    assert main(["run", "x.toml", "--quiet", "--set", "solver.duration=0.004"]) == 0
    summary = json.loads((tmp_path / "runs" / "x" / "summary.json").read_text(encoding="utf-8"))
    assert summary["status"] == "completed"
    assert (
        (tmp_path / "x.toml")
        .read_text(encoding="utf-8")
        .startswith(f"# A perga case made by `perga new {name}`")
    )


def test_refusals_name_the_file_or_the_templates(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["new", "-o", "x.toml"]) == 0  # the default template: separator
    assert main(["new", "-o", "x.toml"]) == 2
    assert "x.toml exists (--overwrite replaces it)" in capsys.readouterr().err
    assert main(["new", "-o", "x.toml", "--overwrite"]) == 0
    assert main(["new", "fed", "-o", "y.toml"]) == 2
    assert "no template 'fed'; there are: single-impact" in capsys.readouterr().err
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "chamber_screen.svg").write_text("mine")
    assert main(["new", "fed-separator", "-o", "z.toml"]) == 2  # a geometry file in the way
    assert (tmp_path / "geometry" / "chamber_screen.svg").read_text() == "mine"
    assert not (tmp_path / "z.toml").exists()


def test_beside_the_same_geometry_file_it_is_kept(tmp_path, monkeypatch, capsys):
    """The README's tour from the repository root: geometry/chamber_screen.svg there holds the
    template's bytes, so the case is written and the file kept, with and without --overwrite
    (in an editable install the file is the template's own); a different file is refused with
    the remedy and nothing is written."""
    root = CASES.parent
    monkeypatch.chdir(root)
    before = (root / "geometry" / "chamber_screen.svg").read_bytes()
    mine = root / f"tour-{tmp_path.name}.toml"
    try:
        for extra in ([], ["--overwrite"]):
            assert main(["new", "fed-separator", "-o", mine.name, *extra]) == 0
            assert (root / "geometry" / "chamber_screen.svg").read_bytes() == before
    finally:
        mine.unlink(missing_ok=True)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "geometry").mkdir()
    (tmp_path / "geometry" / "chamber_screen.svg").write_bytes(before)
    assert main(["new", "fed-separator", "-o", "same.toml"]) == 0
    assert "wrote same.toml; next" in capsys.readouterr().out
    (tmp_path / "geometry" / "chamber_screen.svg").write_bytes(before + b"<!-- mine -->")
    assert main(["new", "fed-separator", "-o", "other.toml"]) == 2
    assert "differs from the template's chamber_screen.svg: write the case into another folder" in (
        capsys.readouterr().err
    )
    assert not (tmp_path / "other.toml").exists()
