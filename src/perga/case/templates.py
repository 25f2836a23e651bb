"""``perga new``: a case to start from, copied from a bundled case with its comments, and the
geometry files it names copied beside it (``geometry/``) so that the new case stands alone."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

CASES = Path(__file__).resolve().parents[3] / "cases"
"""The bundled cases (the source tree's ``cases/``)."""

TEMPLATES = {
    "single-impact": ("single-granule.toml", "one granule struck by one hinged hammer (rigid)"),
    "rebound": ("rebound-test.toml", "a granule thrown at a hammer face: the rebound test"),
    "separator": ("separator.toml", "300 granules, six hinged hammers, rigid contacts"),
    "soft-separator": ("soft-separator.toml", "the separator with soft (linear) contacts"),
    "fed-separator": (
        "bee-bread-separator.toml",
        "comb pieces fed to hammers, release, damage and a screen outlet (the process)",
    ),
}
"""Template name -> (bundled case, what it is)."""

_FILE = re.compile(r'(kind = "file", path = ")([^"]+)(")')


def _same_bytes(a: Path, b: Path) -> bool:
    """Whether files ``a`` and ``b`` exist and hold the same bytes (or are one file)."""
    return b.exists() and (a.resolve() == b.resolve() or a.read_bytes() == b.read_bytes())


def write_template(name: str, out: Path, overwrite: bool = False) -> list[Path]:
    """Write template ``name`` to ``out`` and its geometry files to ``out``'s folder's
    ``geometry/`` (one already there with the same bytes is kept); returns the files written.
    Everything is checked before anything is written: FileExistsError for a file in the way
    (unless ``overwrite``), KeyError for an unknown name."""
    source = CASES / TEMPLATES[name][0]
    text = source.read_text(encoding="utf-8")
    copies = {}
    for match in _FILE.finditer(text):
        geometry = (source.parent / match.group(2)).resolve()
        copies[match.group(2)] = (geometry, out.parent / "geometry" / geometry.name)
    if out.exists() and not overwrite:
        raise FileExistsError(f"{out} exists (--overwrite replaces it)")
    to_copy = [(g, t) for g, t in copies.values() if not _same_bytes(g, t)]
    for geometry, target in to_copy:
        if target.exists() and not overwrite:
            raise FileExistsError(
                f"{target} exists and differs from the template's {geometry.name}: write the "
                "case into another folder (-o DIR/case.toml), or --overwrite replaces it"
            )
    for relative, (_, target) in copies.items():
        text = text.replace(f'path = "{relative}"', f'path = "geometry/{target.name}"')
    header = (
        f"# A perga case made by `perga new {name}` from cases/{source.name}: change it, then\n"
        f"# `perga validate {out.name}` and `perga run {out.name}`. Every key, its unit and its\n"
        "# range: docs/reference/case-files.md, or `perga schema --markdown`.\n\n"
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(header + text, encoding="utf-8")
    for geometry, target in to_copy:
        target.parent.mkdir(exist_ok=True)
        shutil.copyfile(geometry, target)
    return [out, *(t for _, t in to_copy)]
