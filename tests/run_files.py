"""What two run directories are compared by: their tables and ParaView frames, byte for byte
(tests/test_checkpoints.py, tests/test_bundled_cases.py)."""

from __future__ import annotations

import filecmp
import json
from pathlib import Path


def outputs(run: Path) -> list[str]:
    """The run's tables and frames (not its summary, which counts wall time and resumptions,
    nor its checkpoints)."""
    return sorted(
        str(p.relative_to(run))
        for p in run.rglob("*")
        if p.is_file() and "checkpoints" not in p.parts and p.name != "summary.json"
    )


def assert_same_outputs(run: Path, reference: Path, ignore: tuple[str, ...] = ()) -> None:
    assert outputs(run) == outputs(reference)
    differ = [f for f in outputs(reference) if not filecmp.cmp(run / f, reference / f, False)]
    differ = [f for f in differ if f not in ignore]
    assert differ == []


def assert_same_summaries(run: Path, reference: Path) -> None:
    """The two summaries but for the wall time and the speed measured with it."""
    a, b = (json.loads((r / "summary.json").read_text()) for r in (run, reference))
    for summary in (a, b):
        del summary["wall_time"], summary["steps_per_second"]
    assert a == b
