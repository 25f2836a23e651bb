"""The 3-D view of a run (case option ``output.vtk_3d``): the machine as closed triangle meshes,
so that a ParaView scene looks like the machine. Written by :class:`perga.output.vtk.VtkRecorder`
when the system carries a :class:`~perga.model.system.DrawingSpec` (the parts' thicknesses;
the recorders see the system and its frames only, so the case's sizes travel in the system).

Files in ``RUN/vtk/`` (SI units), beside the 2-D ones of :mod:`perga.output.vtk`:

* ``hammers3d.pvd`` + ``hammers3d_NNNNNN.vtu`` and ``rotor3d.pvd`` + ``rotor3d_NNNNNN.vtu``,
  one per frame at the times of ``hammers.pvd``: each hammer, and the rotor disc, as the closed
  mesh of its outline extruded (:func:`perga.geometry.extrude.extrude`) to its thickness, from
  z = −t/2 to +t/2 (centred on the rotor plane z = 0), posed as in ``hammers.pvd`` and
  ``rotor.pvd``; VTK_TRIANGLE cells, outward normals; the cell data of the 2-D file on every
  triangle of its part. The rotor's hinge holes are not drawn (the
  spec carries the disc's outline only; the hammers cover them).
* ``chamber3d.vtu`` (first frame): the wall between its inner outline (as ``chamber.vtu``)
  and that outline offset outwards by the wall thickness along the mitre lines
  (:func:`perga.geometry.wall.wall_pieces`), from −h/2 to +h/2; one closed ring mesh.
* Granules stay points in ``granules.pvd``, which gains point data ``thickness`` (m): the
  ParaView script (``postprocess/paraview/render_run.py --3d``) draws them as cylinder glyphs
  of their radius and thickness, which costs no written geometry per frame.

A part's mesh is extruded once, in its body's frame; a frame only rotates and translates its
vertices (numpy), so the series cost about as much as the 2-D ones.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perga.geometry.extrude import extrude
from perga.geometry.polygon import FloatArray, clean, counter_clockwise, signed_area
from perga.geometry.wall import wall_pieces
from perga.output import vtk_grid
from perga.output.vtk_grid import TRIANGLE, Grid

if TYPE_CHECKING:
    import trimesh


@dataclass(frozen=True)
class Part:
    """A closed mesh in its body's frame: vertices (k, 3), m; triangles (m, 3), indices."""

    vertices: FloatArray
    triangles: NDArray[np.int64]

    @property
    def mesh(self) -> trimesh.Trimesh:
        """The part as a trimesh (for volumes and checks)."""
        import trimesh  # here, not at import: it costs half a second of a run's start

        return trimesh.Trimesh(self.vertices, self.triangles, process=False)


def extruded(outline: ArrayLike, thickness: float) -> Part:
    """``outline`` (m, body frame) extruded from z = −thickness/2 to +thickness/2 (m)."""
    mesh = extrude(outline, thickness, z0=-0.5 * thickness)
    return Part(np.array(mesh.vertices, dtype=float), np.array(mesh.faces, dtype=np.int64))


def _triangles(
    vertices: FloatArray,
    triangles: NDArray[np.int64],
    cell_data: dict[str, NDArray] | None = None,
) -> Grid:
    offsets = np.arange(0, 3 * len(triangles) + 1, 3, dtype=np.int64)
    return vtk_grid.grid(vertices, TRIANGLE, offsets, triangles.ravel(), cell_data=cell_data)


class Machine3D:
    """Parts of the machine (the hammers, or the rotor disc) extruded once (``outlines`` in their
    own frames, m; ``thicknesses``, m); :meth:`mesh` poses them."""

    def __init__(self, outlines: Sequence[ArrayLike], thicknesses: Sequence[float]) -> None:
        parts = [extruded(o, t) for o, t in zip(outlines, thicknesses, strict=True)]
        sizes = [len(p.vertices) for p in parts]
        self.local = np.concatenate([p.vertices for p in parts])
        starts = np.cumsum([0, *sizes[:-1]])
        self.triangles = np.concatenate(
            [p.triangles + s for p, s in zip(parts, starts, strict=True)]
        )
        self.vertex_part = np.repeat(np.arange(len(parts)), sizes)
        self.triangle_counts = np.array([len(p.triangles) for p in parts])

    def mesh(self, origins: FloatArray, angles: FloatArray, cell_data: dict[str, NDArray]) -> Grid:
        """The parts with their frames at ``origins`` (m) turned by ``angles`` (rad);
        ``cell_data`` holds one value per part."""
        angle = np.asarray(angles)[self.vertex_part]
        origin = np.asarray(origins)
        c, s = np.cos(angle), np.sin(angle)
        x, y = self.local[:, 0], self.local[:, 1]
        points = np.column_stack(
            (
                origin[self.vertex_part, 0] + c * x - s * y,
                origin[self.vertex_part, 1] + s * x + c * y,
                self.local[:, 2],
            )
        )
        per_triangle = {
            name: np.repeat(np.asarray(values), self.triangle_counts, axis=0)
            for name, values in cell_data.items()
        }
        return _triangles(points, self.triangles, per_triangle)


def wall(inner: ArrayLike, wall_thickness: float, height: float) -> Part:
    """The chamber wall around ``inner`` (m), ``wall_thickness`` (m) thick, as one closed ring
    mesh from z = −height/2 to +height/2 (m): each mitred wall piece is two triangles of the
    caps, the inner and outer outlines the side walls."""
    p = clean(counter_clockwise(inner))
    _, outer = wall_pieces(p, wall_thickness)
    n = len(p)
    vertices = np.vstack((p, outer))
    triangles = []
    for i, j in itertools.pairwise([*range(n), 0]):
        quad = np.array([i, n + i, n + j, j])  # a convex piece
        if signed_area(vertices[quad]) < 0:
            quad = quad[::-1]
        triangles += [quad[[0, 1, 2]], quad[[0, 2, 3]]]
    import trimesh

    mesh = trimesh.creation.extrude_triangulation(vertices, np.array(triangles), height)
    mesh.apply_translation([0.0, 0.0, -0.5 * height])
    if mesh.volume < 0:
        mesh.invert()
    return Part(np.array(mesh.vertices, dtype=float), np.array(mesh.faces, dtype=np.int64))


def part_grid(part: Part) -> Grid:
    """A part as VTK_TRIANGLE cells."""
    return _triangles(part.vertices, part.triangles)
