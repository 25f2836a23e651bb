"""``perga render``: a preview image of a run from its tables, without ParaView or OpenGL.

Reads the run directory's ``scene.json`` (geometry), ``granules.csv`` and ``hammers.csv``, and
draws with matplotlib (a bare Figure, Agg): the chamber wall, the rotor disc, every hinged or
welded hammer posed from its recorded swing angle and the rotor angle, and the granules as discs
of their true radius coloured by speed (from 0 m/s), at the recorded frame nearest to ``time``
(default: the last). With ``trajectories`` it draws instead the paths in the fixed frame up to
that frame of a few granules (:data:`TRACKS` by default; those with the most impacts, so that a
run of hundreds stays readable), thin, translucent and coloured by speed over the machine at
that frame, as the paper's Fig. 2b (one granule) and Fig. 5a (successive impacts) do. Free
hammers, which the tables do not pose, are not drawn.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

from perga.geometry.polygon import outline_or_circle
from perga.output.scene_file import HammerGeometry, SceneGeometry, read_scene
from perga.output.tables import read_run_table, table_path


def run_table(path: Path) -> np.ndarray:
    """The run table ``path`` names (``RUN/NAME.csv`` or ``RUN/NAME.parquet``), whichever form
    the run has (:func:`~perga.output.tables.read_run_table`), as a structured array of floats
    (names from the header; no rows: empty)."""
    columns = read_run_table(path.parent, path.stem)
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


TRACKS = 8
"""Granule paths ``perga render --trajectories`` draws by default: a few stay readable among
hundreds of granules."""


def sample_tracks(ids: np.ndarray, impacts: np.ndarray | None, count: int) -> np.ndarray:
    """The ids of the ``count`` granules (of ``ids``) whose paths are drawn, reproducibly: those
    with the most granule-hammer impacts in ``impacts`` (impacts.csv's rows; None: not
    recorded), ties and granules without impacts taken in the order of their ids; with no
    impact at all, ids evenly spread over the sorted ids."""
    if count < 1:
        raise ValueError(f"tracks must be >= 1 (got {count})")
    ids = np.unique(ids)
    hits = np.zeros(ids.size, dtype=np.int64)
    if impacts is not None and impacts.size:
        struck, counts = np.unique(impacts["granule"], return_counts=True)
        at = np.searchsorted(ids, struck)
        known = at < ids.size
        known[known] = ids[at[known]] == struck[known]
        hits[at[known]] = counts[known]
    if not hits.any():
        spread = np.linspace(0, ids.size - 1, min(count, ids.size)).round().astype(int)
        return ids[np.unique(spread)]
    return np.sort(ids[np.lexsort((ids, -hits))[:count]])


def _tracks(ax: Axes, granules: np.ndarray, ids: np.ndarray, t: float) -> LineCollection:
    """The paths of granules ``ids`` in the fixed frame up to time ``t`` (s) onto ``ax``: one
    collection, thin translucent segments coloured by the granule's speed at each segment's
    end, a ring where each path starts and a dot where it is at ``t``."""
    lines, speeds, starts, ends = [], [], [], []
    for i in ids:
        path = granules[(granules["id"] == i) & (granules["time"] <= t)]
        xy = np.column_stack([path["x"], path["y"]])
        lines += list(np.stack([xy[:-1], xy[1:]], axis=1))
        speeds += list(path["speed"][1:])
        starts.append(xy[0])
        ends.append(xy[-1])
    segments = LineCollection(
        lines, array=np.array(speeds), cmap="plasma", lw=0.8, alpha=0.75, zorder=3
    )
    segments.set_clim(*speed_range(np.array(speeds)))
    ax.add_collection(segments)
    ax.scatter(*np.transpose(starts), s=14, facecolors="none", edgecolors="0.2", lw=0.7, zorder=4)
    ax.scatter(*np.transpose(ends), s=10, color="k", zorder=4, gid="track ends")
    return segments


def draw(
    run: Path,
    *,
    time: float | None = None,
    trajectories: bool = False,
    tracks: int = TRACKS,
    colorbar: bool = True,
) -> tuple[Figure, float]:
    """Draw run directory ``run`` (module doc; ``tracks``: the granule paths drawn with
    ``trajectories``, :func:`sample_tracks`) with a colour bar unless ``colorbar`` is False;
    returns the figure and the time of the frame drawn, s."""
    scene = read_scene(run)
    granules = run_table(run / "granules.csv")
    hammers = run_table(run / "hammers.csv")
    times = np.unique(granules["time"])
    t = times[-1] if time is None else times[np.argmin(np.abs(times - time))]
    fig = Figure(figsize=(7, 7), dpi=120)  # no pyplot: no GUI backend, no global state
    ax = fig.subplots()
    chamber = _machine(ax, scene, hammers[hammers["time"] == t])
    if trajectories:
        impacts = run_table(run / "impacts.csv") if table_path(run, "impacts") else None
        struck = None if impacts is None else impacts[impacts["time"] <= t]
        ids = sample_tracks(granules["id"][granules["time"] <= t], struck, tracks)
        mapped = _tracks(ax, granules, ids, float(t))
        every = granules["id"][granules["time"] == t].size
        how = "most impacts" if struck is not None and struck.size else "spread by id"
        title = f"paths of {ids.size} of {every} granules ({how}) to t = {t:.4g} s"
    else:
        now = granules[granules["time"] == t]
        mapped = PatchCollection(
            [Circle((x, y), r) for x, y, r in zip(now["x"], now["y"], now["radius"], strict=True)],
            array=now["speed"],
            cmap="plasma",
        )
        mapped.set_clim(*speed_range(now["speed"]))
        ax.add_collection(mapped)
        title = f"t = {t:.4g} s"
    if colorbar:
        fig.colorbar(mapped, ax=ax, label="speed, m/s", shrink=0.8)
    ax.set_xlim(-1.05 * chamber, 1.05 * chamber)
    ax.set_ylim(-1.05 * chamber, 1.05 * chamber)
    ax.set_aspect("equal")
    ax.set_xlabel("x, m")
    ax.set_ylabel("y, m")
    ax.set_title(f"{run.name}: {title}")
    return fig, float(t)


def _machine(ax: Axes, scene: SceneGeometry, frame: np.ndarray) -> float:
    """The chamber wall, the rotor disc and the hinged and welded hammers posed at the hammer
    table's ``frame`` onto ``ax``; returns the half-width to show, m."""
    wall = (
        outline_or_circle(scene.chamber_outline, scene.chamber_radius, 256)
        if scene.chamber_radius is not None
        else None
    )
    if wall is not None:
        ax.add_patch(Polygon(wall, closed=True, fill=False, color="0.3", lw=1.5))
    disc = outline_or_circle(scene.rotor_outline, scene.rotor_radius, 256)
    ax.add_patch(Polygon(disc, closed=True, fill=False, color="0.75", lw=1, ls="--"))
    rotor_angle = float(frame["swing_angle"][frame["id"] == -1][0])
    polys = [
        Polygon(
            _hammer_outline(h, rotor_angle, float(frame["swing_angle"][frame["id"] == i][0])),
            closed=True,
        )
        for i, h in enumerate(scene.hammers)
        if h.mount != "free"
    ]
    ax.add_collection(PatchCollection(polys, facecolor="0.55", edgecolor="0.2"))
    return float(np.abs(wall).max()) if wall is not None else 1.2 * scene.rotor_radius


def render(
    run: Path,
    out: Path,
    *,
    time: float | None = None,
    trajectories: bool = False,
    tracks: int = TRACKS,
    colorbar: bool = True,
) -> float:
    """Draw run directory ``run`` into the PNG ``out`` (:func:`draw`); returns the time of the
    frame drawn, s."""
    fig, t = draw(run, time=time, trajectories=trajectories, tracks=tracks, colorbar=colorbar)
    fig.savefig(out)
    return t
