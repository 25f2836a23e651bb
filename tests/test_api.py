"""The top-level Python API: light to import, each name where the docstring says, and its
refusals."""

import subprocess
import sys
from pathlib import Path

import pytest

import perga

ROOT = Path(__file__).resolve().parents[1]


def test_import_perga_loads_nothing_heavy():
    code = "import sys, perga; print(sorted({'numba', 'pymunk', 'scipy'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_names_and_refusals(tmp_path):
    assert set(perga.__all__) >= {"load_case", "Simulation", "simulate", "load_run", "evaluate"}
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        perga.nope  # noqa: B018
    case = ROOT / "cases" / "single-granule.toml"
    summary = perga.simulate(case, tmp_path / "run", overrides=["solver.duration=0.005"])
    assert summary.status == "completed"
    with pytest.raises(FileExistsError, match="already holds a run"):
        perga.simulate(case, tmp_path / "run")
    with pytest.raises(perga.CaseError, match=r"rotor\.rpm"):
        perga.simulate(case, tmp_path / "bad", overrides=["rotor.rpm=-1"])
    run = perga.load_run(tmp_path / "run")
    frame = run.dataframe("granules")
    assert (
        list(frame.columns)[:4] == ["time", "id", "x", "y"]
        and len(frame) == run.granules["id"].size
    )
    with pytest.raises(ValueError, match="no table 'trajectories'"):
        run.dataframe("trajectories")


def test_the_package_doc_names_only_commands_that_exist():
    """Every ``perga COMMAND [--option]`` that help(perga) names is a command with those options
    (it named a ``perga metrics --list`` that does not exist)."""
    import re

    import perga
    from perga.cli import build_parser

    commands = build_parser()._subparsers._group_actions[0].choices
    named = re.findall(r"`perga ([a-z-]+)((?: --?[a-z-]+)*)`", perga.__doc__)
    assert named
    for command, options in named:
        assert command in commands, command
        known = {o for a in commands[command]._actions for o in a.option_strings}
        assert set(options.split()) <= known, (command, options)
