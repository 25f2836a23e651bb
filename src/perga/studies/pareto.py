"""The Pareto front of a set of settings over several objectives, each maximised or minimised
(Deb, Multi-Objective Optimization using Evolutionary Algorithms, 2001, ch. 2): a row dominates
another when it is at least as good in every column and strictly better in one; the front is the
rows no row dominates."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

SENSES = ("max", "min")
"""Each objective's sense: to be maximised or minimised."""


def pareto_front(values: ArrayLike, senses: Sequence[str]) -> np.ndarray:
    """The indices (ascending) of the non-dominated rows of ``values``, shape (n, k), column j
    to be maximised (``senses[j] == "max"``) or minimised (``"min"``). A row with any nan is
    never on the front and dominates no row; identical rows are all kept (neither dominates the
    other). ValueError on values not 2-D, or senses not one of :data:`SENSES` per column
    (naming the bad ones)."""
    array = np.asarray(values, dtype=float)
    if array.ndim != 2:
        raise ValueError(f"values: an (n, k) array, got shape {array.shape}")
    if len(senses) != array.shape[1]:
        raise ValueError(f"senses: one per column ({array.shape[1]}), got {len(senses)}")
    bad = [f"{j}: {s!r}" for j, s in enumerate(senses) if s not in SENSES]
    if bad:
        raise ValueError(f"senses: each 'max' or 'min'; got {', '.join(bad)}")
    sign = np.array([1.0 if s == "max" else -1.0 for s in senses])
    rows = np.flatnonzero(~np.isnan(array).any(axis=1))
    gain = array[rows] * sign  # every column now to be maximised
    front = [
        i
        for i, row in zip(rows, gain, strict=True)
        if not ((gain >= row).all(axis=1) & (gain > row).any(axis=1)).any()
    ]
    return np.array(front, dtype=int)
