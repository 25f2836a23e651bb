"""Faults met as a user meets them (issue 15, item 3): real stop signals sent to a running
``perga run`` at seeded random moments, a full disk (a small tmpfs mounted for the run in a
user namespace), an output path that cannot be a directory. Each leaves a run that reads
back whole (:func:`assert_readable`), a clean message and the documented exit status."""

from __future__ import annotations

import csv
import json
import random
import shlex
import shutil
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import meshio
import pytest

ROOT = Path(__file__).resolve().parents[1]
SEPARATOR = ROOT / "cases" / "separator.toml"
GRANULE_COLUMNS = [
    "time",
    "id",
    "x",
    "y",
    "vx",
    "vy",
    "angular_velocity",
    "speed",
    "radius",
    "mass",
]
"""The columns every granules.csv begins with (a process run adds held, survival, ...)."""


def perga(*args: str) -> subprocess.Popen[str]:
    """``perga ARGS`` in a subprocess (the console script's module), stderr captured."""
    return subprocess.Popen(
        [sys.executable, "-m", "perga.cli", *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


def assert_readable(run: Path) -> dict:
    """Every table of ``run`` ends on a whole row and parses; each ``.pvd`` is valid XML whose
    every frame exists and reads; the summary is strict JSON. Returns the summary."""
    summary = json.loads(
        (run / "summary.json").read_text(), parse_constant=lambda c: pytest.fail(f"JSON has {c}")
    )
    for table in run.glob("*.csv"):
        text = table.read_bytes()
        assert text.endswith(b"\r\n"), f"{table.name} ends inside a row"
        with table.open(newline="") as f:
            rows = list(csv.reader(f))
        assert all(len(r) == len(rows[0]) for r in rows), table.name
    granules = run / "granules.csv"
    if granules.exists():
        with granules.open(newline="") as f:
            header = next(csv.reader(f))
        assert header[: len(GRANULE_COLUMNS)] == GRANULE_COLUMNS, header
    for index in (run / "vtk").glob("*.pvd"):
        entries = ET.parse(index).getroot().findall("./Collection/DataSet")
        for entry in entries:
            frame = run / "vtk" / entry.get("file")
            assert frame.exists(), f"{index.name} refers to a missing {frame.name}"
            meshio.read(frame)
    return summary


def _completed(run: Path) -> bool:
    """Whether the run in ``run`` had reached its end (a signal then comes as the process exits)."""
    summary = run / "summary.json"
    return summary.exists() and json.loads(summary.read_text())["status"] == "completed"


@pytest.mark.parametrize(
    ("signum", "seed"),
    [(signal.SIGINT, 1), (signal.SIGTERM, 2), (signal.SIGHUP, 3), (signal.SIGTERM, 4)],
)
def test_a_stop_signal_at_a_random_moment_leaves_a_readable_run(tmp_path, signum, seed):
    """The signal arrives at a seeded moment from interpreter start-up to the middle of the
    run: the process exits with 128 + the signal's number and no traceback, and a run directory,
    if it was made, reads whole and its summary says what stopped it."""
    out = tmp_path / "run"
    moment = random.Random(seed).uniform(0.05, 4.0)
    proc = perga("run", str(SEPARATOR), "-o", str(out), "--quiet")
    time.sleep(moment)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    name = signal.Signals(signum).name
    if proc.returncode == 0 or _completed(out):  # finished already: not this test's question
        pytest.skip(f"the run ended before {moment:.2f} s")
    assert proc.returncode in (128 + signum, -signum), (moment, err)
    assert "Traceback" not in err, err
    if proc.returncode == -signum:  # before Python ran perga's code: nothing made
        assert not out.exists()
        return
    assert f"{name}" in err or "interrupted" in err, err
    if (out / "summary.json").exists():
        summary = assert_readable(out)
        assert summary["status"] == "interrupted"
        assert name in summary["reason"]
    else:  # stopped before the run began writing
        assert not out.exists() or not any(out.iterdir())


def test_a_stop_signal_mid_run_stops_at_a_step_with_every_frame_written(tmp_path):
    """SIGTERM once frames are on disk: the run stops at the next step boundary, its summary
    counts the frames the tables and the .pvd hold."""
    out = tmp_path / "run"
    proc = perga("run", str(SEPARATOR), "-o", str(out), "--quiet")
    deadline = time.monotonic() + 60
    while not (out / "vtk" / "granules.pvd").exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    time.sleep(0.3)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "interrupted" in err and "Traceback" not in err
    summary = assert_readable(out)
    assert summary["status"] == "interrupted" and "SIGTERM" in summary["reason"]
    assert 0 < summary["simulated_time"] < 0.5
    frames = ET.parse(out / "vtk" / "granules.pvd").getroot().findall("./Collection/DataSet")
    with (out / "granules.csv").open(newline="") as f:
        times = {row["time"] for row in csv.DictReader(f)}
    assert len(frames) == len(times) == summary["frames"]


def _children(pid: int) -> list[int]:
    """The processes ``pid`` started (Linux's /proc)."""
    found = Path(f"/proc/{pid}/task").glob("*/children")
    return [int(c) for path in found for c in path.read_text().split()]


def _running(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, ended but not yet reaped, does not)."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat.rpartition(")")[2].split()[0] != "Z"


def test_a_killed_run_leaves_its_paraview_writer_to_finish_and_exit(tmp_path):
    """SIGKILL (the OOM killer) once frames are on disk: the run's ParaView writer process,
    left alone, writes the frames it was sent, exits, and leaves every series readable."""
    out = tmp_path / "run"
    proc = perga("run", str(SEPARATOR), "-o", str(out), "--quiet")
    index, deadline = out / "vtk" / "granules.pvd", time.monotonic() + 60
    while (not index.exists() or index.read_text().count("<DataSet") < 3) and (
        time.monotonic() < deadline
    ):
        time.sleep(0.02)
    (writer,) = _children(proc.pid)
    proc.kill()
    proc.communicate(timeout=60)
    while _running(writer) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not _running(writer), "the writer process outlived the run"
    frames = ET.parse(out / "vtk" / "granules.pvd").getroot().findall("./Collection/DataSet")
    assert len(frames) >= 3
    for index in (out / "vtk").glob("*.pvd"):
        for entry in ET.parse(index).getroot().findall("./Collection/DataSet"):
            meshio.read(out / "vtk" / entry.get("file"))


def _unshare_works() -> bool:
    """Whether this machine lets a process mount a file system of its own (a user namespace)."""
    if shutil.which("unshare") is None:
        return False
    probe = ["unshare", "--mount", "--map-root-user", "true"]
    return subprocess.run(probe, capture_output=True).returncode == 0


needs_unshare = pytest.mark.skipif(
    not _unshare_works(), reason="needs unshare (user namespaces) to mount a small tmpfs"
)


def run_on_a_small_disk(size: str, out: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``perga run ARGS`` writing into a tmpfs of ``size`` (e.g. '150k') mounted for it alone
    (a real file system that fills up: writes fail with ENOSPC); the run directory is copied
    to ``out`` before the mount goes away."""
    disk = out.parent / "disk"
    disk.mkdir()
    perga_run = " ".join(
        shlex.quote(a) for a in (sys.executable, "-m", "perga.cli", "run", *args, "-o")
    )
    script = (
        f"mount -t tmpfs -o size={size} tmpfs {disk} && "
        f"{perga_run} {disk}/run --quiet; status=$?; cp -a {disk}/run {out}; exit $status"
    )
    command = ["unshare", "--mount", "--map-root-user", "sh", "-c", script]
    return subprocess.run(command, capture_output=True, text=True, timeout=300)


TABLES = '["granules", "hammers", "energy", "impacts"]'
ALL_RECORDS = '["granules", "hammers", "energy", "impacts", "vtk"]'


@needs_unshare
@pytest.mark.parametrize("record", [TABLES, '["vtk"]', ALL_RECORDS])
def test_a_full_disk_stops_the_run_with_whole_files(tmp_path, record):
    """A 150 kB disk fills within the first frames (a frame is ~25 kB of ParaView file and
    ~30 kB of granule table; tables alone, ParaView files alone, both): exit 1 with one clear
    message (no traceback, no VTK error pages), every file whole, the summary says the disk was
    full."""
    out = tmp_path / "run"
    done = run_on_a_small_disk(
        "150k", out, str(SEPARATOR), "--set", "solver.duration=0.05",
        "--set", f"output.record={record}",
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "could not write its output" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and "ERR|" not in done.stderr, done.stderr
    summary = assert_readable(out)
    assert summary["status"] == "failed"
    assert "No space left on device" in summary["reason"] or "OutOfDiskSpace" in summary["reason"]


@needs_unshare
def test_a_disk_with_room_lets_the_same_run_complete(tmp_path):
    """The other side: the same run on a 20 MB disk completes (it writes about 3 MB)."""
    out = tmp_path / "run"
    done = run_on_a_small_disk(
        "20m", out, str(SEPARATOR), "--set", "solver.duration=0.05",
        "--set", f"output.record={ALL_RECORDS}",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert assert_readable(out)["status"] == "completed"


@pytest.mark.parametrize("where", ["a file", "under a file"])
def test_an_output_path_that_cannot_be_a_directory_is_bad_input(tmp_path, where):
    from perga.cli import main

    blocker = tmp_path / "blocker"
    blocker.write_text("not a directory")
    target = blocker if where == "a file" else blocker / "run"
    assert main(["run", str(SEPARATOR), "-o", str(target), "--quiet"]) == 2
    assert blocker.read_text() == "not a directory"
