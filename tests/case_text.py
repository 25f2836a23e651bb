"""Bundled case files as text, for tests that edit them by whole lines."""

import re
from pathlib import Path

TRAILING_COMMENT = re.compile(r"^([^#\n]*?)[ \t]+#.*$", re.MULTILINE)
"""A key line's trailing comment (``key = value  # unit: meaning``); whole-line comments stay."""


def case_text(path: Path) -> str:
    """The text of case file ``path`` without its key lines' trailing comments, so that an edit
    may name a line with what ends it (``"mass = 0.02826\\n"``)."""
    return TRAILING_COMMENT.sub(r"\1", path.read_text(encoding="utf-8"))
