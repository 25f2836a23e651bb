"""The outline of a closed mesh cut by the rotor plane z = height: an outer polygon and holes.

Units: m. trimesh and scipy's graph tools are imported where a mesh is cut, not with the
module: a run whose parts are outlines never loads them (half a second of every run's start).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from perga.geometry.mass import check_closed, load_mesh
from perga.geometry.polygon import FloatArray, clean, contains, signed_area
from perga.geometry.units import GeometryError

if TYPE_CHECKING:
    import trimesh


@dataclass(frozen=True)
class Section:
    """outline: outer polygon (n, 2), m, counter-clockwise; holes: inner polygons, clockwise."""

    outline: FloatArray
    holes: tuple[FloatArray, ...]


def _loops(segments: FloatArray, tol: float, source: str) -> list[FloatArray]:
    """Chain 2-D segments (n, 2, 2) into closed loops of points; merges ends closer than tol."""
    ends = segments.reshape(-1, 2)
    from scipy.sparse import coo_matrix  # here, as trimesh (module doc)
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    pairs = cKDTree(ends).query_pairs(tol, output_type="ndarray")
    n = len(ends)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, node = connected_components(graph, directed=False)
    edges = {tuple(sorted(e)) for e in node.reshape(-1, 2) if e[0] != e[1]}
    neighbours: dict[int, list[int]] = {}
    for a, b in edges:
        neighbours.setdefault(a, []).append(b)
        neighbours.setdefault(b, []).append(a)
    position = {int(k): ends[i] for i, k in enumerate(node)}
    for k, around in neighbours.items():
        if len(around) != 2:
            x, y = position[k]
            raise GeometryError(
                f"{source}: the section is not made of closed loops at ({x:.6g}, {y:.6g}) m "
                f"({len(around)} section edges meet there)"
            )
    loops: list[FloatArray] = []
    unvisited = set(neighbours)
    while unvisited:
        start = unvisited.pop()
        loop, previous, current = [start], start, neighbours[start][0]
        while current != start:
            unvisited.discard(current)
            loop.append(current)
            a, b = neighbours[current]
            previous, current = current, (b if a == previous else a)
        loops.append(np.array([position[k] for k in loop]))
    return loops


def section_mesh(
    mesh: trimesh.Trimesh, height: float | None = None, source: str = "mesh"
) -> Section:
    """Cut a closed mesh (m) by the plane z = height (m; None: half-way up the mesh).

    GeometryError naming ``source`` for an open or non-manifold mesh, a plane that misses the
    mesh (or only touches it), a section of several separate parts or of open chains.
    """
    check_closed(mesh, source)
    (_, _, z_min), (_, _, z_max) = mesh.bounds
    z = 0.5 * (z_min + z_max) if height is None else float(height)
    scale = float(np.linalg.norm(mesh.extents))
    tol = 1e-9 * scale
    if not (z_min + tol < z < z_max - tol):
        raise GeometryError(
            f"{source}: the section plane z = {z:.6g} m misses the mesh "
            f"(it spans z = {z_min:.6g} .. {z_max:.6g} m)"
        )
    import trimesh  # here, not at import (module doc)

    segments = trimesh.intersections.mesh_plane(mesh, [0.0, 0.0, 1.0], [0.0, 0.0, z])
    if len(segments) == 0:
        raise GeometryError(f"{source}: the section plane z = {z:.6g} m misses the mesh")
    loops = [clean(loop) for loop in _loops(np.asarray(segments)[:, :, :2], tol, source)]
    loops = [loop for loop in loops if len(loop) >= 3]
    if not loops:
        raise GeometryError(f"{source}: the section at z = {z:.6g} m has no area")
    loops.sort(key=lambda loop: -abs(signed_area(loop)))
    outer = loops[0] if signed_area(loops[0]) > 0 else loops[0][::-1].copy()
    holes = []
    for loop in loops[1:]:
        if not contains(outer, loop[0]):
            raise GeometryError(
                f"{source}: the section at z = {z:.6g} m has {len(loops)} loops, not all "
                "inside the largest one: one part per file"
            )
        holes.append(loop if signed_area(loop) < 0 else loop[::-1].copy())
    return Section(outer, tuple(holes))


def section_file(path: str | Path, units: str, height: float | None = None) -> Section:
    """``section_mesh`` of the mesh file ``path`` in ``units``; height in m (after scaling)."""
    return section_mesh(load_mesh(path, units), height, str(path))
