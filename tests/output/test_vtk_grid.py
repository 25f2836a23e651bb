"""``vtk_grid``: an array streamed piece by piece ends as the bytes of one ``zlib.compress``
over it, and a grid holding it compressed is the file a grid holding the array writes."""

import zlib
from pathlib import Path

import numpy as np
import pytest

from perga.output import vtk_grid
from perga.output.vtk_grid import ZLIB_LEVEL, ArrayStream


@pytest.mark.parametrize("pieces", [1, 7, 300])
def test_a_stream_is_the_whole_array_compressed_at_once(tmp_path: Path, pieces: int) -> None:
    """Rows of a random walk (as trajectories are) in ``pieces`` uneven pieces."""
    rows = np.cumsum(np.random.default_rng(pieces).normal(size=(30_000, 3)), axis=0)
    stream = ArrayStream(tmp_path / "points.z", np.float64, 3)
    cuts = np.sort(np.random.default_rng(0).choice(np.arange(1, len(rows)), pieces - 1, False))
    for piece in np.split(rows, cuts):
        stream.add(piece)
    array = stream.finish()
    assert array.block == zlib.compress(rows.tobytes(), ZLIB_LEVEL)
    assert (array.rows, array.components, array.size) == (30_000, 3, rows.nbytes)
    assert not (tmp_path / "points.z").exists()


def test_a_grid_of_compressed_arrays_writes_the_same_file(tmp_path: Path) -> None:
    """Points and point data given compressed (and an empty stream: no rows) or as arrays."""
    rng = np.random.default_rng(1)
    points, speed = rng.normal(size=(50, 3)), rng.random(50)
    streams = {}
    for name, values, k in (("points", points, 3), ("speed", speed, 1), ("none", [], 1)):
        streams[name] = ArrayStream(tmp_path / f"{name}.z", np.float64, k)
        streams[name].add(np.asarray(values, dtype=float).reshape(-1, k) if k > 1 else values)
    done = {name: stream.finish() for name, stream in streams.items()}
    offsets, connectivity = np.array([0, 20, 50]), np.arange(50)[::-1].copy()
    line = vtk_grid.POLY_LINE
    plain = vtk_grid.grid(points, line, offsets, connectivity, {"speed": speed, "none": []})
    packed = vtk_grid.Grid(
        done["points"], line, offsets, connectivity, {"speed": done["speed"], "none": done["none"]}
    )
    vtk_grid.save(plain, tmp_path / "plain.vtu")
    vtk_grid.save(packed, tmp_path / "packed.vtu")
    assert (tmp_path / "plain.vtu").read_bytes() == (tmp_path / "packed.vtu").read_bytes()
