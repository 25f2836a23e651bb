"""Unstructured grids built from NumPy arrays and written as ``.vtu`` files, through VTK itself.

Every ParaView file of a run goes through here: :func:`grid` makes a ``vtkUnstructuredGrid`` of
one cell type from points, cell offsets and connectivity, with point and cell data; :func:`save`
writes it with VTK's XML writer, binary data zlib-compressed inline (base64) in each
``DataArray``, the layout pyvista writes (ParaView reads every layout; meshio 5.3 misreads the
raw appended one, whose offsets VTK pads with spaces: meshio issue #1135). VTK is called
directly rather than through pyvista, whose objects cost about 1.5 ms more per 300-granule frame
to build and save than the write itself (docs/dev/performance.md); the files hold the same arrays.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonCore import vtkPoints
from vtkmodules.vtkCommonDataModel import (
    VTK_POLY_LINE,
    VTK_POLYGON,
    VTK_TRIANGLE,
    VTK_VERTEX,
    vtkCellArray,
    vtkDataSetAttributes,
    vtkUnstructuredGrid,
)
from vtkmodules.vtkCommonMisc import vtkErrorCode
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridWriter

from perga.output.files import write_new

VERTEX, POLY_LINE, POLYGON, TRIANGLE = VTK_VERTEX, VTK_POLY_LINE, VTK_POLYGON, VTK_TRIANGLE
"""The cell types perga writes."""
ZLIB_LEVEL = 1
"""zlib's fastest level: a 300-granule frame 1 % larger than at VTK's default (5), written in
0.6 ms less (docs/dev/performance.md)."""


def grid(
    points: ArrayLike,
    cell_type: int,
    offsets: ArrayLike,
    connectivity: ArrayLike,
    point_data: Mapping[str, ArrayLike] | None = None,
    cell_data: Mapping[str, ArrayLike] | None = None,
) -> vtkUnstructuredGrid:
    """Cells of ``cell_type``, cell c through the points ``connectivity[offsets[c]:offsets[c +
    1]]``, over ``points`` ((n, 2) lifted to z = 0, or (n, 3)), with data arrays by name (one
    value or row per point or cell). The grid refers to the arrays without copying them
    (``numpy_to_vtk``'s arrays hold a reference to their NumPy array)."""
    xyz = np.asarray(points, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] not in (2, 3):
        raise ValueError(f"points must be (n, 2) or (n, 3), got shape {xyz.shape}")
    if xyz.shape[1] == 2:
        xyz = np.column_stack((xyz, np.zeros(len(xyz))))
    out = vtkUnstructuredGrid()
    vtk_points = vtkPoints()
    vtk_points.SetData(numpy_to_vtk(np.ascontiguousarray(xyz), deep=False))
    out.SetPoints(vtk_points)
    cells = vtkCellArray()
    cells.SetData(_ids(offsets), _ids(connectivity))
    out.SetCells(cell_type, cells)
    _add(out.GetPointData(), point_data or {})
    _add(out.GetCellData(), cell_data or {})
    return out


def vertices(
    points: ArrayLike, point_data: Mapping[str, ArrayLike] | None = None
) -> vtkUnstructuredGrid:
    """Each point of ``points`` ((n, 2), m) with its own VTK_VERTEX cell, and ``point_data``."""
    xy = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    index = np.arange(len(xy) + 1, dtype=np.int64)
    return grid(xy, VERTEX, index, index[:-1], point_data)


def save(mesh: vtkUnstructuredGrid, path: Path) -> None:
    """Write ``mesh`` to ``path`` (.vtu): binary, zlib at ``ZLIB_LEVEL``, inline. VTK writes
    the file into memory and perga writes it to disk whole (:func:`~perga.output.files.
    write_new`): VTK's own file writing crashed the process (a segmentation fault, a corrupted
    heap) when a disk filled up in the middle of a file, and was slower than writing into
    memory (docs/dev/performance.md). A failed write leaves no file and raises OSError."""
    writer = vtkXMLUnstructuredGridWriter()
    writer.SetInputData(mesh)
    writer.SetDataModeToBinary()
    writer.SetCompressorTypeToZLib()
    writer.SetCompressionLevel(ZLIB_LEVEL)
    writer.WriteToOutputStringOn()
    errors: list[str] = []
    for source in (writer, writer.GetExecutive()):
        source.AddObserver("ErrorEvent", lambda _obj, _event: errors.append("VTK error"))
    if writer.Write() != 1 or errors:
        code = writer.GetErrorCode()
        raise OSError(f"VTK could not make {path}: {vtkErrorCode.GetStringFromErrorCode(code)}")
    write_new(Path(path), writer.GetOutputString().encode("utf-8"))


def _ids(values: ArrayLike) -> object:
    return numpy_to_vtkIdTypeArray(np.ascontiguousarray(values, dtype=np.int64), deep=False)


def _add(attributes: vtkDataSetAttributes, arrays: Mapping[str, ArrayLike]) -> None:
    for name, values in arrays.items():
        array = np.ascontiguousarray(values)
        if array.dtype == bool:
            array = array.astype(np.uint8)
        vtk_array = numpy_to_vtk(array, deep=False)
        vtk_array.SetName(name)
        attributes.AddArray(vtk_array)
