"""``perga render RUN --process``: the separator as a process over time, from a run's tables.

Three panels: the granules present in the chamber (granules.csv, per frame) and the cumulative
counts released from comb cells (releases.csv) and gone through the outlet (outflow.csv); the
mass flow through the outlet, kg/s, per interval between frames; and, with damage, the expected
survival of the granules that left. A table the run did not write leaves its curve out.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from perga.output.figures import new_figure, save
from perga.output.render import run_table
from perga.output.tables import table_path

FLOW_BINS = 30
"""Intervals of the run the mass flow is averaged over (fewer if the run has fewer frames)."""


def mass_flow(times: np.ndarray, masses: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Mass flow, kg/s, in each interval [edges[i], edges[i+1]) (the last one closed) of the
    departures at ``times`` (s) with ``masses`` (kg): the mass in the interval over its length.
    Summed with the lengths it is the mass of the departures within [edges[0], edges[-1]]."""
    mass, _ = np.histogram(times, bins=edges, weights=masses)
    return mass / np.diff(edges)


def _optional(path: Path) -> np.ndarray | None:
    return run_table(path) if table_path(path.parent, path.stem) is not None else None


def process_figure(run: Path, out: Path) -> None:
    """Draw the process panels of run directory ``run`` into the PNG ``out``."""
    granules = run_table(run / "granules.csv")
    releases = _optional(run / "releases.csv")
    outflow = _optional(run / "outflow.csv")
    frames, present = np.unique(granules["time"], return_counts=True)
    damage = outflow is not None and "survival" in (granules.dtype.names or ())
    fig, axes = new_figure((6.5, 8.5 if damage else 6.0), 3 if damage else 2, 1)
    ax = axes[0]
    ax.plot(frames, present, label="in the chamber", color="0.3")
    for table, label, colour in ((releases, "released from cells", "C0"),
                                 (outflow, "gone through the outlet", "C1")):  # fmt: skip
        if table is not None and table["time"].size:
            t = np.sort(table["time"])
            ax.step(np.r_[0.0, t], np.arange(t.size + 1), where="post", label=label, color=colour)
    ax.set_ylabel("granules")
    ax.legend(loc="upper left")
    ax = axes[1]
    if outflow is not None and frames.size > 1:
        edges = np.linspace(frames[0], frames[-1], min(FLOW_BINS, frames.size - 1) + 1)
        ax.stairs(mass_flow(outflow["time"], outflow["mass"], edges) * 1e3, edges, color="C1")
    ax.set_ylabel("mass flow through the outlet, g/s")
    ax.set_xlabel("time, s")
    if damage:
        assert outflow is not None
        ax = axes[2]
        ax.hist(outflow["survival"], bins=np.linspace(0.0, 1.0, 21), color="C2")
        ax.set_xlabel("expected survival of the granules that left")
        ax.set_ylabel("granules")
    fig.suptitle(f"{run.name}: the process")
    save(fig, out)
