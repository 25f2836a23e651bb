"""Whether two ``trajectories.vtu`` files hold the same lines: per granule (cell ``id``) the
same points, times and speeds in the same order, whatever the order of the points in the file
(it changed from granule by granule to frame by frame)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyvista as pv


def lines(path: Path) -> dict[int, np.ndarray]:
    """Each granule's line in ``path``: rows (x, y, z, time, speed) in the line's order."""
    mesh = pv.read(path)
    data = np.column_stack((mesh.points, mesh.point_data["time"], mesh.point_data["speed"]))
    ids = mesh.cell_data["id"]
    return {int(ids[c]): data[mesh.get_cell(c).point_ids] for c in range(mesh.n_cells)}


def same_lines(a: Path, b: Path) -> bool:
    """The two files' lines equal bit for bit."""
    first, second = lines(a), lines(b)
    return first.keys() == second.keys() and all(
        first[k].tobytes() == second[k].tobytes() for k in first
    )
