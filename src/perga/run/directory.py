"""A run directory: made empty (or refused), the case copied into it as run, its digest."""

from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import tomli_w

from perga.case.schema import Case


def prepare_directory(directory: Path, overwrite: bool) -> None:
    """Create the run directory; refuse a non-empty one unless ``overwrite`` (FileExistsError)."""
    if directory.exists() and any(directory.iterdir()):
        if not overwrite:
            raise FileExistsError(
                f"{directory} already holds a run: choose another -o DIR or pass --overwrite"
            )
        shutil.rmtree(directory)
    directory.mkdir(parents=True, exist_ok=True)


def write_case_copy(case: Case, case_path: Path, destination: Path) -> None:
    """The case as run: the file itself, or with overrides the file's data with them applied
    (TOML, the overrides listed in a comment at the top)."""
    if not case.overrides or case.source_data is None:
        shutil.copyfile(case_path, destination)
        return
    header = "".join(f"# --set {shown(o)}\n" for o in case.overrides)
    text = f"# {case_path} as run, with these overrides:\n{header}\n" + tomli_w.dumps(
        case.source_data, multiline_strings=True
    )
    destination.write_text(text, encoding="utf-8")


def shown(override: str, most: int = 200) -> str:
    """An override as listed in a run's case copy and summary: whole, or cut after ``most``
    characters (an explicit placement of a run's granules, ``perga run --from``, is in the
    case copy itself)."""
    if len(override) <= most:
        return override
    return f"{override[: most // 2]}... ({len(override)} characters)"


def case_digest(directory: Path) -> str:
    """SHA-256 of the run's copy of its case file."""
    return hashlib.sha256((directory / "case.toml").read_bytes()).hexdigest()
