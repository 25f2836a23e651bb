"""What the checks of a run's episodes against their models share (impacts,
:mod:`perga.stats.impact_law`; slides, :mod:`perga.stats.slide_law`; flights,
:mod:`perga.stats.flight_law`): their regimes in words and the spread of their errors."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np


def in_words(regimes: Counter[str]) -> str:
    """Counted regimes in words, most frequent first ("none" without any)."""
    return "; ".join(f"{n} {why}" for why, n in regimes.most_common()) or "none"


def median_and_largest(columns: dict[str, list[float]]) -> dict[str, dict[str, float]]:
    """Median and largest of each column's finite values, by column (a column with none is
    left out)."""
    out = {}
    for name, values in columns.items():
        finite = np.array([v for v in values if math.isfinite(v)])
        if finite.size:
            out[name] = {"median": float(np.median(finite)), "max": float(finite.max())}
    return out
