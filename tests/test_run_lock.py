"""One run per run directory: a run holds an OS lock on its directory for its whole life, and a
second ``perga run`` into it (``--overwrite`` or ``--resume`` included) refuses at once, exit
2, touching nothing; once the first has ended the directory is free again."""

from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from perga.run.directory import LOCK, DirectoryLock, DirectoryLockedError
from tests.run_files import assert_same_outputs
from tests.test_checkpoints import perga, start
from tests.test_faults import assert_readable

ROOT = Path(__file__).resolve().parents[1]
FIRST = ["solver.duration=0.3"]
"""The rigid separator's first 0.3 s: 6-12 s of wall time on 2 cores, long enough for the
second run to start, load its case and be refused while the first writes."""


@pytest.mark.slow  # five perga processes, three whole runs: 11-13 s
def test_a_second_run_into_a_directory_being_written_is_refused(tmp_path: Path) -> None:
    """Two real processes: the second, with --overwrite (and a --resume), is refused with the
    first's pid while the first writes; the directory then holds exactly the first run's
    outputs (those of the same run into a directory of its own); after it ends a run with
    --overwrite takes the directory and leaves no lock file."""
    out, reference = tmp_path / "run", tmp_path / "reference"
    first = start("separator.toml", out, FIRST)
    deadline = time.monotonic() + 120
    while not (out / "granules.csv").exists():
        assert time.monotonic() < deadline and first.poll() is None, "the first run never wrote"
        time.sleep(0.02)
    case = str(ROOT / "cases" / "separator.toml")
    refused = [
        perga("run", case, "-o", str(out), "--overwrite", "--quiet", "--set", "rotor.rpm=900"),
        perga("run", "--resume", str(out), "--quiet"),
    ]
    assert first.poll() is None, "the first run ended before the second was refused"
    for second in refused:
        assert second.returncode == 2
        assert second.stderr == (
            f"error: {out} is being written by another perga run (pid {first.pid})\n"
        )
    assert first.wait(timeout=300) == 0
    assert assert_readable(out)["status"] == "completed"
    assert start("separator.toml", reference, FIRST).wait(timeout=300) == 0
    assert_same_outputs(out, reference)
    again = perga("run", case, "-o", str(out), "--overwrite", "--quiet",
                  "--set", "solver.duration=0.01")  # fmt: skip
    assert again.returncode == 0, again.stderr
    assert assert_readable(out)["simulated_time"] == pytest.approx(0.01)
    assert not (out / LOCK).exists()


def test_the_lock_names_its_holder_and_is_free_once_released(tmp_path: Path) -> None:
    """In one process too: a second lock on the directory is refused naming this pid; the
    lock released, it can be taken again, and its file is gone."""
    held = pytest.raises(DirectoryLockedError, match=rf"\(pid {os.getpid()}\)")
    with DirectoryLock(tmp_path / "run"), held:
        DirectoryLock(tmp_path / "run")
    DirectoryLock(tmp_path / "run").release()
    assert list((tmp_path / "run").iterdir()) == []
