"""A run of a case with geometry files is complete on its own: the files copied into
RUN/geometry/ with their SHA-256 digests, its case.toml pointing at the copies, so that it
resumes, reports and compares wherever it is moved. The slow test kills every bundled case
with a geometry file after its first checkpoint, moves it, resumes it and compares it byte for
byte with a run that never stopped (benchmarks/kill_resume.py --geometry does the same at
random moments, many times)."""

from __future__ import annotations

import hashlib
import random
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

from perga.case import load_case
from perga.cli import main
from perga.run.directory import changed_geometry, write_case_copy
from tests.run_files import assert_same_outputs
from tests.test_checkpoints import perga, start

ROOT = Path(__file__).resolve().parents[1]
GEOMETRY_CASES = {
    path.name: ["solver.duration=0.03", "output.checkpoint_every=0.005"]
    for path in sorted((ROOT / "cases").glob("*.toml"))
    if 'kind = "file"' in path.read_text(encoding="utf-8")
}
"""Every bundled case with a geometry file -> the overrides that shorten it to 0.03 s with a
checkpoint every 0.005 s (2-5 s of wall time each on 2 cores)."""


def _file_paths(case_file: Path) -> list[str]:
    """The path of every geometry file the case file names (kind = "file"), as written."""
    case = load_case(case_file)
    shapes = (case.rotor.shape, case.hammers.shape, case.chamber and case.chamber.shape)
    return [s.path for s in shapes if getattr(s, "kind", None) == "file"]


def test_the_bundled_cases_with_geometry_files_are_found() -> None:
    assert set(GEOMETRY_CASES) >= {"bee-bread-separator.toml", "stepped-hammers.toml"}


@pytest.mark.parametrize("name", sorted(GEOMETRY_CASES))
def test_a_runs_case_points_at_its_copies_with_their_digests(tmp_path: Path, name: str) -> None:
    """The run's case.toml names each geometry file as geometry/NAME, a copy of the original
    byte for byte whose SHA-256 geometry/SHA256SUMS records; loaded from the run directory it
    is the case as run but for those paths; a copy changed afterwards is named."""
    original = ROOT / "cases" / name
    run = tmp_path / "run"
    run.mkdir()
    write_case_copy(load_case(original), original, run / "case.toml")
    paths = _file_paths(run / "case.toml")
    assert paths and all(p.startswith("geometry/") for p in paths)
    sources = [(original.parent / p).resolve() for p in _file_paths(original)]
    recorded = dict(
        reversed(line.split("  "))
        for line in (run / "geometry" / "SHA256SUMS").read_text().splitlines()
    )
    assert sorted(recorded) == sorted({p.removeprefix("geometry/") for p in paths})
    for source, copy in zip(sources, paths, strict=True):
        content = (run / copy).read_bytes()
        assert content == source.read_bytes()
        assert recorded[copy.removeprefix("geometry/")] == hashlib.sha256(content).hexdigest()
    as_run, as_given = load_case(run / "case.toml").model_dump(), load_case(original).model_dump()
    for dumped in (as_run, as_given):
        for part in ("rotor", "hammers", "chamber"):
            if dumped[part] and (dumped[part]["shape"] or {}).get("kind") == "file":
                dumped[part]["shape"]["path"] = "-"
    assert as_run == as_given
    assert changed_geometry(run) == []
    (run / paths[0]).write_bytes((run / paths[0]).read_bytes() + b"\n")
    assert changed_geometry(run) == [
        f"{run / paths[0]}: changed since the run copied it (its SHA-256 is not the one in "
        f"{run / 'geometry' / 'SHA256SUMS'})"
    ]


def test_a_moved_run_with_a_geometry_file_reports_and_compares(tmp_path: Path, capsys) -> None:
    """The first 5 ms of the case with hammers drawn in an SVG file, moved where its case's
    relative path leads nowhere: perga report and perga compare read it (before the copies:
    exit 2, "cannot read"), and perga run --from takes its granules with its own case.toml."""
    first, moved = tmp_path / "a" / "run", tmp_path / "b" / "c" / "run"
    case = str(ROOT / "cases" / "geometry-hammers.toml")
    sets = ["--set", "solver.duration=0.005"]
    assert main(["run", case, "-o", str(first), "--quiet", *sets]) == 0
    moved.parent.mkdir(parents=True)
    shutil.move(first, moved)
    assert main(["report", str(moved)]) == 0
    assert main(["compare", str(moved), "-o", str(tmp_path / "compare")]) in (0, 1)
    again = ["run", str(moved / "case.toml"), "--from", str(moved), "-o", str(tmp_path / "from")]
    assert main([*again, "--quiet", *sets]) == 0
    assert "Traceback" not in capsys.readouterr().err


def _between_first_checkpoints(out: Path, proc: subprocess.Popen[str]) -> float:
    """Wait for the run's second checkpoint file; the wall time since its first, s."""
    deadline, seen = time.monotonic() + 300, {}
    while len(seen) < 2:
        assert time.monotonic() < deadline and proc.poll() is None, "too few checkpoints"
        for path in (out / "checkpoints").glob("step-*.ckpt"):
            seen.setdefault(path.name, time.monotonic())
        time.sleep(0.01)
    first, second = sorted(seen.values())[:2]
    return second - first


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(GEOMETRY_CASES))
def test_a_killed_run_with_geometry_files_resumes_moved_to_the_same_bytes(
    tmp_path: Path, name: str
) -> None:
    """The case and its geometry files copied into a folder of their own and run from there;
    SIGKILL at a seeded moment after the checkpoint that follows the first (at t = 0), within
    as long again as lay between the two (four of the six checkpoint intervals are left); the
    run directory moved two folders deeper and the case's folder removed, as on another
    machine; perga run --resume: the tables and ParaView frames equal an uninterrupted run's
    byte for byte, and its case.toml compiles from the copies alone (perga validate)."""
    source = tmp_path / "source"
    shutil.copytree(ROOT / "geometry", source / "geometry")
    case = source / "cases" / name
    case.parent.mkdir()
    shutil.copyfile(ROOT / "cases" / name, case)
    sets = GEOMETRY_CASES[name]
    reference, out = tmp_path / "reference", tmp_path / "run"
    assert start(str(case), reference, sets).wait(timeout=600) == 0
    proc = start(str(case), out, sets)
    interval = _between_first_checkpoints(out, proc)
    time.sleep(random.Random(name).uniform(0.0, 1.0) * interval)
    proc.send_signal(signal.SIGKILL)
    assert proc.wait(timeout=60) == -signal.SIGKILL, "the run ended before the signal"
    moved = tmp_path / "elsewhere" / "deeper" / "run"
    moved.parent.mkdir(parents=True)
    shutil.move(out, moved)
    shutil.rmtree(source)
    resumed = perga("run", "--resume", str(moved), "--quiet")
    assert resumed.returncode == 0, resumed.stderr
    assert_same_outputs(moved, reference)
    assert main(["validate", str(moved / "case.toml")]) == 0
