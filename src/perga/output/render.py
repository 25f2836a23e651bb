"""``perga render``: a preview image of a run from its tables, without ParaView or OpenGL.

Reads the run directory's ``scene.json`` (geometry), ``granules.csv`` and ``hammers.csv``, and
draws with matplotlib (a bare Figure, Agg): the chamber wall, the rotor disc, every hinged or
welded hammer posed from its recorded swing angle and the rotor angle, and the granules as discs
of their true radius coloured by speed (from 0 m/s), at the recorded frame nearest to ``time``
(default: the last). With ``trajectories`` it draws instead every granule's path in the fixed
frame up to that frame, coloured by time, as the paper's Fig. 2b (one granule) and Fig. 5a
(successive impacts) do. Free hammers, which the tables do not pose, are not drawn.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

from perga.geometry.polygon import outline_or_circle
from perga.output.scene_file import HammerGeometry, read_scene
from perga.output.tables import read_columns, table_path


def run_table(path: Path) -> np.ndarray:
    """A run table (``NAME.csv``, or its Parquet form ``NAME.parquet``) as a structured array
    of floats (names from the header; no rows: empty)."""
    found = table_path(path.parent, path.stem)
    if found is None:
        raise FileNotFoundError(f"{path}: missing (record it with output.record)")
    columns = read_columns(found)
    n = len(next(iter(columns.values()), []))
    out = np.zeros(n, dtype=[(name, float) for name in columns])
    for name, values in columns.items():
        out[name] = values
    return out


def speed_range(speeds: np.ndarray) -> tuple[float, float]:
    """The colour scale of speeds, m/s: from 0 to the fastest (to 1 when nothing moves)."""
    fastest = float(np.max(speeds, initial=0.0))
    return 0.0, fastest if fastest > 0.0 else 1.0


def _hammer_outline(h: HammerGeometry, rotor_angle: float, alpha: float) -> np.ndarray:
    """World vertices (m) of a hinged or welded hammer at rotor angle and swing angle α."""
    hinge = np.array(h.hinge)
    c, s = math.cos(rotor_angle), math.sin(rotor_angle)
    hinge = np.array([c * hinge[0] - s * hinge[1], s * hinge[0] + c * hinge[1]])
    a = rotor_angle + h.angle_on_rotor + alpha
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return hinge + h.outline @ rot.T


def render(
    run: Path,
    out: Path,
    *,
    time: float | None = None,
    trajectories: bool = False,
    colorbar: bool = True,
) -> float:
    """Draw run directory ``run`` into the PNG ``out`` (with a colour bar unless ``colorbar`` is
    False); returns the time of the frame drawn, s."""
    scene = read_scene(run)
    granules = run_table(run / "granules.csv")
    hammers = run_table(run / "hammers.csv")
    times = np.unique(granules["time"])
    t = times[-1] if time is None else times[np.argmin(np.abs(times - time))]
    fig = Figure(figsize=(7, 7), dpi=120)  # no pyplot: no GUI backend, no global state
    ax = fig.subplots()
    wall = (
        outline_or_circle(scene.chamber_outline, scene.chamber_radius, 256)
        if scene.chamber_radius is not None
        else None
    )
    chamber = float(np.abs(wall).max()) if wall is not None else 1.2 * scene.rotor_radius
    if wall is not None:
        ax.add_patch(Polygon(wall, closed=True, fill=False, color="0.3", lw=1.5))
    disc = outline_or_circle(scene.rotor_outline, scene.rotor_radius, 256)
    ax.add_patch(Polygon(disc, closed=True, fill=False, color="0.75", lw=1, ls="--"))
    frame = hammers[hammers["time"] == t]
    rotor_angle = float(frame["swing_angle"][frame["id"] == -1][0])
    polys = []
    for i, h in enumerate(scene.hammers):
        if h.mount != "free":
            alpha = float(frame["swing_angle"][frame["id"] == i][0])
            polys.append(Polygon(_hammer_outline(h, rotor_angle, alpha), closed=True))
    ax.add_collection(PatchCollection(polys, facecolor="0.55", edgecolor="0.2"))
    if trajectories:
        lines, stamps = [], []
        drawn = granules[granules["time"] <= t]
        for i in np.unique(drawn["id"]):
            path = drawn[drawn["id"] == i]
            xy = np.column_stack([path["x"], path["y"]])
            lines += list(np.stack([xy[:-1], xy[1:]], axis=1))
            stamps += list(path["time"][1:])
        segments = LineCollection(lines, array=np.array(stamps), cmap="viridis", lw=1.2)
        ax.add_collection(segments)
        if colorbar:
            fig.colorbar(segments, ax=ax, label="time, s", shrink=0.8)
        title = f"trajectories in the fixed frame to t = {t:.4g} s"
    else:
        now = granules[granules["time"] == t]
        discs = PatchCollection(
            [Circle((x, y), r) for x, y, r in zip(now["x"], now["y"], now["radius"], strict=True)],
            array=now["speed"],
            cmap="plasma",
        )
        discs.set_clim(*speed_range(now["speed"]))
        ax.add_collection(discs)
        if colorbar:
            fig.colorbar(discs, ax=ax, label="speed, m/s", shrink=0.8)
        title = f"t = {t:.4g} s"
    ax.set_xlim(-1.05 * chamber, 1.05 * chamber)
    ax.set_ylim(-1.05 * chamber, 1.05 * chamber)
    ax.set_aspect("equal")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.set_title(f"{run.name}: {title}")
    fig.savefig(out)
    return float(t)
