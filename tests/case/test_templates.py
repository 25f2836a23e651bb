"""perga new: every template is written with its geometry beside it into an empty folder, and
runs from there; refusals name what is in the way."""

import json

import pytest

from perga.case.templates import TEMPLATES
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
