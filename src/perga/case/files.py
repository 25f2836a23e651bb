"""The geometry files a case names: its tables of ``kind = "file"`` (a hammer, rotor or chamber
shape read from an STL, OBJ, SVG, DXF or points file), found in the case's data."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any


def file_tables(data: object) -> Iterator[dict[str, Any]]:
    """Every table of a case's data (TOML as dicts and lists) that names a geometry file: its
    ``kind`` is "file" and its ``path`` a string, relative to the case's folder or absolute."""
    if isinstance(data, dict):
        if data.get("kind") == "file" and isinstance(data.get("path"), str):
            yield data
        for value in data.values():
            yield from file_tables(value)
    elif isinstance(data, list):
        for value in data:
            yield from file_tables(value)
