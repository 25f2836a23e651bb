"""The same case and seed give byte-identical output (issue 15, item 6): two runs of the rigid
and the soft separator, every table and every ParaView file compared byte for byte (the wall
time in summary.json is the only thing allowed to differ, and the checkpoints, which carry the
summary so far, are not compared)."""

import json
from pathlib import Path

import pytest

from perga.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize(
    ("case", "duration"), [("separator.toml", "0.05"), ("soft-separator.toml", "0.02")]
)
def test_two_runs_of_a_case_write_the_same_bytes(case, duration, tmp_path):
    runs = [tmp_path / "a", tmp_path / "b"]
    for run in runs:
        args = ["run", str(ROOT / "cases" / case), "-o", str(run), "--quiet"]
        assert main([*args, "--set", f"solver.duration={duration}"]) == 0
    files = sorted(p.relative_to(runs[0]) for p in runs[0].rglob("*") if p.is_file())
    files = [f for f in files if f.parts[0] != "checkpoints"]
    assert (
        sorted(
            p.relative_to(runs[1])
            for p in runs[1].rglob("*")
            if p.is_file() and "checkpoints" not in p.parts
        )
        == files
    )
    assert any(f.suffix == ".vtu" for f in files) and any(f.suffix == ".csv" for f in files)
    for name in files:
        if name == Path("summary.json"):
            a, b = (json.loads((run / name).read_text()) for run in runs)
            for summary in (a, b):
                del summary["wall_time"], summary["steps_per_second"]
            assert a == b
        else:
            assert (runs[0] / name).read_bytes() == (runs[1] / name).read_bytes(), name
