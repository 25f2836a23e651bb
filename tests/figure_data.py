"""The figures a command saved, kept for their data (issue 18, item 6: a plot's data must match
its table, not merely exist): ``saved = saved_figures(monkeypatch)`` before the command, then
``saved["energy.png"]`` is the matplotlib Figure written to a file of that name."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.figure import Figure


def saved_figures(monkeypatch: pytest.MonkeyPatch) -> dict[str, Figure]:
    """Every Figure saved from now on, by its file's name (the last one of a name)."""
    saved: dict[str, Figure] = {}
    savefig = Figure.savefig

    def keep(fig: Figure, fname, *args, **kwargs):
        saved[str(getattr(fname, "name", fname)).rsplit("/", 1)[-1]] = fig
        return savefig(fig, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", keep)
    return saved


def lines(ax) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """An axes' lines by label (unlabelled: "_lineN"), as (x, y) arrays."""
    return {
        line.get_label(): (np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float))
        for line in ax.get_lines()
    }


def bar_heights(ax) -> np.ndarray:
    """The heights of an axes' histogram bars, in drawing order."""
    return np.array([patch.get_height() for patch in ax.patches])
