"""Figures for reports without pyplot: no GUI backend, no global state, nothing to close."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from matplotlib.figure import Figure


def new_figure(
    figsize: tuple[float, float], nrows: int = 1, ncols: int = 1, **options: Any
) -> tuple[Figure, Any]:
    """A figure of ``figsize`` inches and its axes (``Figure.subplots`` with ``options``)."""
    fig = Figure(figsize=figsize, layout=options.pop("layout", None))
    return fig, fig.subplots(nrows, ncols, **options)


def save(fig: Figure, path: Path, dpi: int = 110) -> bool:
    """Lay ``fig`` out and write it to ``path`` (PNG by its suffix); returns True."""
    if fig.get_layout_engine() is None:
        fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    return True
