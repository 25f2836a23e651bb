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


def write_template(name: str, out: Path, overwrite: bool = False) -> list[Path]:
    """Write template ``name`` to ``out`` and its geometry files to ``out``'s folder's
    ``geometry/``; returns the files written. FileExistsError for a file in the way (unless
    ``overwrite``), KeyError for an unknown name."""
    source = CASES / TEMPLATES[name][0]
    text = source.read_text(encoding="utf-8")
    copies = {}
    for match in _FILE.finditer(text):
        geometry = (source.parent / match.group(2)).resolve()
        copies[match.group(2)] = (geometry, out.parent / "geometry" / geometry.name)
    for target in [out, *(t for _, t in copies.values())]:
        if target.exists() and not overwrite:
            raise FileExistsError(f"{target} exists (--overwrite replaces it)")
    for relative, (_, target) in copies.items():
        text = text.replace(f'path = "{relative}"', f'path = "geometry/{target.name}"')
    header = (
        f"# A perga case made by `perga new {name}` from cases/{source.name}: change it, then\n"
        f"# `perga validate {out.name}` and `perga run {out.name}`. Every key, its unit and its\n"
        "# range: docs/case-files.md, or `perga schema --markdown`.\n\n"
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(header + text, encoding="utf-8")
    for geometry, target in copies.values():
        target.parent.mkdir(exist_ok=True)
        shutil.copyfile(geometry, target)
    return [out, *(t for _, t in copies.values())]
