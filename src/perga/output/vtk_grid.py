"""Unstructured grids built from NumPy arrays and written as ``.vtu`` files (VTK's XML format).

Every ParaView file of a run goes through here: :func:`grid` gathers the points, cells (one
type) and point and cell data of a grid; :func:`save` writes it as VTK's XML
``UnstructuredGrid`` with every array zlib-compressed (level :data:`ZLIB_LEVEL`) in one raw
``AppendedData`` section, header type UInt64, no padding (the layout VTK's readers, ParaView,
pyvista and meshio read).

perga writes the file itself rather than through VTK's objects: building a
``vtkUnstructuredGrid`` from NumPy arrays costs about 1 ms of Python a 300-granule frame. Here
the arrays' bytes go to ``zlib.compress`` and the XML is a few lines of text
(docs/dev/performance.md). An array too long to hold, or known only piece by piece, goes
through an :class:`ArrayStream` (one zlib stream, the bytes ``zlib.compress`` gives for the
whole array) and into the grid as the :class:`Compressed` array it ends as.
"""

from __future__ import annotations

import zlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perga.output.files import write_new

VERTEX, POLY_LINE, POLYGON, TRIANGLE = 1, 4, 7, 5
"""The VTK cell types perga writes (VTK_VERTEX, VTK_POLY_LINE, VTK_POLYGON, VTK_TRIANGLE)."""
ZLIB_LEVEL = 1
"""zlib's fastest level: a 300-granule frame 1 % larger than at VTK's default (5), written in
0.6 ms less (docs/dev/performance.md)."""
TYPES = {
    np.dtype(np.float64): "Float64",
    np.dtype(np.float32): "Float32",
    np.dtype(np.int64): "Int64",
    np.dtype(np.int32): "Int32",
    np.dtype(np.uint8): "UInt8",
}
"""VTK's names of the array types written; booleans are written as UInt8."""


@dataclass(frozen=True)
class Compressed:
    """An array already through zlib: its type, values per row (1 or 3), rows, and its zlib
    block (one stream of its little-endian bytes)."""

    dtype: np.dtype
    components: int
    rows: int
    block: bytes

    @property
    def size(self) -> int:
        """The array's bytes before compression."""
        return self.rows * self.components * self.dtype.itemsize


class ArrayStream:
    """An array of ``dtype`` with ``components`` values per row, its rows added piece by piece
    (:meth:`add`) through one zlib stream into the file ``path``: the stream's bytes are those
    of ``zlib.compress`` over the whole array, however the rows come in pieces. Not picklable
    (a zlib stream is not): whoever holds one rebuilds it from the rows."""

    def __init__(self, path: Path, dtype: type, components: int = 1) -> None:
        self.path = path
        self.dtype = np.dtype(dtype).newbyteorder("<")
        self.components = components
        self.rows = 0
        self._zlib = zlib.compressobj(ZLIB_LEVEL)
        self._file: BinaryIO = open(path, "wb")  # noqa: SIM115 (closed by finish())

    def add(self, values: ArrayLike) -> None:
        """Append the rows ``values`` ((rows, components), or (rows,) for one component)."""
        array = np.ascontiguousarray(values, dtype=self.dtype)
        self.rows += len(array)
        self._file.write(self._zlib.compress(array.tobytes()))

    def finish(self) -> Compressed:
        """The array as it ends (the file read back and removed)."""
        self._file.write(self._zlib.flush())
        self._file.close()
        block = self.path.read_bytes()
        self.path.unlink()
        return Compressed(self.dtype, self.components, self.rows, block)


@dataclass(frozen=True)
class Grid:
    """An unstructured grid: points (n, 3), m; cells of one VTK type, cell c through the points
    ``connectivity[offsets[c]:offsets[c + 1]]``; data arrays by name, a value or row per point
    or cell. The points and the data arrays may be :class:`Compressed` already."""

    points: NDArray[np.float64] | Compressed
    cell_type: int
    offsets: NDArray[np.int64]
    connectivity: NDArray[np.int64]
    point_data: dict[str, NDArray | Compressed] = field(default_factory=dict)
    cell_data: dict[str, NDArray | Compressed] = field(default_factory=dict)

    @property
    def cells(self) -> int:
        """The number of cells."""
        return len(self.offsets) - 1


def grid(
    points: ArrayLike,
    cell_type: int,
    offsets: ArrayLike,
    connectivity: ArrayLike,
    point_data: Mapping[str, ArrayLike] | None = None,
    cell_data: Mapping[str, ArrayLike] | None = None,
) -> Grid:
    """Cells of ``cell_type``, cell c through the points ``connectivity[offsets[c]:offsets[c +
    1]]``, over ``points`` ((n, 2) lifted to z = 0, or (n, 3)), with data arrays by name (one
    value or row per point or cell)."""
    xyz = np.asarray(points, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] not in (2, 3):
        raise ValueError(f"points must be (n, 2) or (n, 3), got shape {xyz.shape}")
    if xyz.shape[1] == 2:
        xyz = np.column_stack((xyz, np.zeros(len(xyz))))
    return Grid(
        xyz,
        cell_type,
        np.asarray(offsets, dtype=np.int64),
        np.asarray(connectivity, dtype=np.int64),
        {k: _array(v) for k, v in (point_data or {}).items()},
        {k: _array(v) for k, v in (cell_data or {}).items()},
    )


def vertices(points: ArrayLike, point_data: Mapping[str, ArrayLike] | None = None) -> Grid:
    """Each point of ``points`` ((n, 2), m) with its own VTK_VERTEX cell, and ``point_data``."""
    xy = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    index = np.arange(len(xy) + 1, dtype=np.int64)
    return grid(xy, VERTEX, index, index[:-1], point_data)


def save(mesh: Grid, path: Path) -> None:
    """Write ``mesh`` to ``path`` (.vtu, module doc), whole or not at all
    (:func:`~perga.output.files.write_new`: a failed write leaves no file and raises
    OSError)."""
    blocks: list[bytes] = []
    offset = 0

    def arrays(data: Mapping[str, NDArray | Compressed], indent: str) -> str:
        nonlocal offset
        lines = []
        for name, values in data.items():
            array = values if isinstance(values, Compressed) else _compressed(values)
            block = _appended(array)
            several = array.components > 1
            components = f'NumberOfComponents="{array.components}" ' if several else ""
            lines.append(
                f'{indent}<DataArray type="{TYPES[array.dtype]}" Name="{name}" '
                f'{components}format="appended" offset="{offset}"/>\n'
            )
            blocks.append(block)
            offset += len(block)
        return "".join(lines)

    cells = {
        "connectivity": mesh.connectivity,
        "offsets": mesh.offsets[1:],
        "types": np.full(mesh.cells, mesh.cell_type, dtype=np.uint8),
    }
    head = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
        'header_type="UInt64" compressor="vtkZLibDataCompressor">\n'
        "  <UnstructuredGrid>\n"
        f'    <Piece NumberOfPoints="{_rows(mesh.points)}" NumberOfCells="{mesh.cells}">\n'
        f"      <PointData>\n{arrays(mesh.point_data, '        ')}      </PointData>\n"
        f"      <CellData>\n{arrays(mesh.cell_data, '        ')}      </CellData>\n"
        f"      <Points>\n{arrays({'Points': mesh.points}, '        ')}      </Points>\n"
        f"      <Cells>\n{arrays(cells, '        ')}      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        '  <AppendedData encoding="raw">\n   _'
    )
    tail = "\n  </AppendedData>\n</VTKFile>\n"
    write_new(Path(path), b"".join([head.encode(), *blocks, tail.encode()]))


def _array(values: ArrayLike) -> NDArray:
    """``values`` as a contiguous array of a type :data:`TYPES` names (booleans as UInt8)."""
    array = np.ascontiguousarray(values)
    if array.dtype == bool:
        array = array.astype(np.uint8)
    elif array.dtype not in TYPES:
        array = array.astype(np.int64 if array.dtype.kind in "iu" else np.float64)
    return array


def _rows(values: NDArray | Compressed) -> int:
    """The rows of an array, compressed or not."""
    return values.rows if isinstance(values, Compressed) else len(values)


def _compressed(values: NDArray) -> Compressed:
    """``values`` through zlib, one block of the whole array."""
    raw = np.ascontiguousarray(values).astype(values.dtype.newbyteorder("<"), copy=False)
    components = values.shape[1] if values.ndim == 2 else 1
    return Compressed(raw.dtype, components, len(raw), zlib.compress(raw.tobytes(), ZLIB_LEVEL))


def _appended(array: Compressed) -> bytes:
    """An array's appended data: VTK's compression header (UInt64: blocks, block size, size of
    a partial last block (0: none), each block's compressed size) and the zlib block; one block
    of the whole array, none for an empty one."""
    if array.size == 0:
        return np.array([0, 0, 0], dtype="<u8").tobytes()
    return np.array([1, array.size, 0, len(array.block)], dtype="<u8").tobytes() + array.block
