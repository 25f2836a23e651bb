"""Other commits of this repository checked out beside it, for side-by-side benchmarks."""

from __future__ import annotations

import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def worktree(ref: str) -> Path:
    """A temporary checkout of ``ref`` (made once per commit, then reused); returns its
    src/ folder."""
    sha = subprocess.run(
        ["git", "-C", str(ROOT), "rev-parse", "--short", ref],
        capture_output=True, text=True, check=True,
    ).stdout.strip()  # fmt: skip
    path = Path(tempfile.gettempdir()) / f"perga-{sha}"
    if not path.exists():
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(path), sha],
            capture_output=True, check=True,
        )  # fmt: skip
    return path / "src"
