"""Closed 3-D meshes of planar parts: an outline (with holes) extruded along z (trimesh,
imported where a mesh is made, not with the module: it costs half a second of a run's start)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from perga.geometry.convex import triangulate
from perga.geometry.polygon import as_points, contains, counter_clockwise, signed_area

if TYPE_CHECKING:
    import trimesh


def _cap(outline: ArrayLike, holes: Sequence[ArrayLike]) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and counter-clockwise triangles covering the outline minus its holes."""
    outer = counter_clockwise(outline)
    if not holes:
        return outer, np.array(triangulate(outer))
    loops = [outer, *(as_points(h) for h in holes)]
    vertices = np.vstack(loops)
    from scipy.spatial import Delaunay

    triangles = Delaunay(vertices).simplices
    centres = vertices[triangles].mean(axis=1)
    keep = [contains(outer, c) and not any(contains(h, c) for h in loops[1:]) for c in centres]
    triangles = triangles[np.array(keep)]
    # Delaunay keeps every boundary edge here only if the boundary is finely enough divided:
    # the kept triangles must cover exactly the outline minus the holes
    covered = sum(abs(signed_area(vertices[t])) for t in triangles)
    expected = abs(signed_area(outer)) - sum(abs(signed_area(h)) for h in loops[1:])
    if abs(covered - expected) > 1e-9 * expected:
        raise ValueError("cannot triangulate the part with holes: refine its boundary")
    a, b, c = vertices[triangles[:, 0]], vertices[triangles[:, 1]], vertices[triangles[:, 2]]
    flip = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    triangles[flip < 0] = triangles[flip < 0][:, ::-1]
    return vertices, triangles


def extrude(
    outline: ArrayLike, thickness: float, holes: Sequence[ArrayLike] = (), z0: float = 0.0
) -> trimesh.Trimesh:
    """A closed mesh of the outline minus holes (m) from z = z0 to z0 + thickness (m)."""
    vertices, triangles = _cap(outline, holes)
    import trimesh

    mesh = trimesh.creation.extrude_triangulation(vertices, triangles, thickness)
    mesh.apply_translation([0.0, 0.0, z0])
    if mesh.volume < 0:
        mesh.invert()
    return mesh
