"""Paths to every value of nested tables and arrays, for the fuzz tests that mutate case and
study files (tests/case/test_fuzz.py, tests/studies/test_study_fuzz.py)."""

from __future__ import annotations

from typing import Any


def value_paths(data: Any, path: tuple = ()) -> list[tuple]:
    """Paths (tuples of keys and indices) to every value in nested dicts and lists, tables and
    arrays included."""
    out = [path] if path else []
    if isinstance(data, dict):
        for key, value in data.items():
            out += value_paths(value, (*path, key))
    elif isinstance(data, list):
        for i, value in enumerate(data):
            out += value_paths(value, (*path, i))
    return out
