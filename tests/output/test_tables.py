"""CSV tables: a block written as columns reads back to the same float64 bits as one written row
by row, each block is on disk when the call returns, and a wrong shape is refused."""

from __future__ import annotations

import csv
import subprocess
import sys

import numpy as np
import pytest

from perga.output import tables
from perga.output.tables import ParquetTable, Table, open_table, read_columns, table_path

VALUES = np.array(
    [0.1, 1e-05, 1.0, 0.0, -0.0, -2.5e300, 5e-324, 1 / 3, 2.0**53 + 2, np.nan, np.inf, -np.inf]
)


def _read(path) -> list[list[str]]:
    with path.open(newline="") as f:
        return list(csv.reader(f))


def test_columns_read_back_bit_for_bit_and_like_rows(tmp_path) -> None:
    ids = np.arange(VALUES.size, dtype=np.int64)
    rows = Table(tmp_path / "rows.csv", ["x", "id"])
    rows.write(zip(VALUES.tolist(), ids.tolist(), strict=True))
    cols = Table(tmp_path / "cols.csv", ["x", "id"])
    cols.write_columns([VALUES, ids])
    assert cols.rows == rows.rows == VALUES.size
    for table in (rows, cols):
        table.close()
    a, b = _read(tmp_path / "rows.csv"), _read(tmp_path / "cols.csv")
    assert a[0] == b[0] == ["x", "id"]
    got = np.array([float(r[0]) for r in b[1:]])
    np.testing.assert_array_equal(got.view(np.int64)[~np.isnan(got)],
                                  VALUES.view(np.int64)[~np.isnan(VALUES)])  # fmt: skip
    assert np.isnan(got).sum() == 1
    assert [r[1] for r in a[1:]] == [r[1] for r in b[1:]]  # integers as integers
    assert (tmp_path / "cols.csv").read_bytes().count(b"\r\n") == VALUES.size + 1


def test_a_block_is_on_disk_when_write_returns(tmp_path) -> None:
    table = Table(tmp_path / "t.csv", ["a", "b"])
    table.write_columns([np.array([1.5, 2.5]), np.array([3, 4])])
    assert _read(tmp_path / "t.csv") == [["a", "b"], ["1.5", "3"], ["2.5", "4"]]
    table.close()


@pytest.mark.parametrize("count", [1, 3])
def test_a_wrong_number_of_columns_is_refused(tmp_path, count) -> None:
    table = Table(tmp_path / "t.csv", ["a", "b"])
    with pytest.raises(ValueError, match="header has 2"):
        table.write_columns([np.zeros(2)] * count)
    table.close()


# --- the Parquet granule table ----------------------------------------------------------------


def _frames(n_frames: int, n: int) -> list[list[np.ndarray]]:
    rng = np.random.default_rng(3)
    return [
        [np.full(n, 0.01 * k), np.arange(n, dtype=np.int64), rng.normal(size=n)]
        for k in range(n_frames)
    ]


def test_parquet_parts_are_written_when_full_and_read_back_exactly(tmp_path, monkeypatch) -> None:
    """Parts of PART_ROWS rows appear while writing (each complete, no temporary file visible
    to readers); at close the rest; the dataset reads back bit for bit, in order, like CSV."""
    monkeypatch.setattr(tables, "PART_ROWS", 250)
    frames = _frames(7, 100)
    parquet = ParquetTable(tmp_path / "g.parquet", ["time", "id", "x"])
    csv_table = Table(tmp_path / "g.csv", ["time", "id", "x"])
    for k, frame in enumerate(frames):
        parquet.write_columns(frame)
        csv_table.write_columns(frame)
        assert len(list((tmp_path / "g.parquet").glob("part-*.parquet"))) == (k + 1) // 3
    csv_table.close()
    parquet.close()
    parquet.close()
    assert sorted(p.name for p in (tmp_path / "g.parquet").iterdir()) == [
        "part-00000.parquet", "part-00001.parquet", "part-00002.parquet"
    ]  # fmt: skip
    a, b = read_columns(tmp_path / "g.csv"), read_columns(tmp_path / "g.parquet")
    assert list(a) == list(b) == ["time", "id", "x"]
    for name in a:
        assert np.array_equal(a[name], b[name])
    assert np.array_equal(b["x"], np.concatenate([f[2] for f in frames]))


def test_parquet_rows_like_columns(tmp_path) -> None:
    table = ParquetTable(tmp_path / "e.parquet", ["time", "granule"])
    table.write([(0.5, 3), (0.75, 4)])
    table.write([])
    table.close()
    back = read_columns(tmp_path / "e.parquet")
    assert list(back) == ["time", "granule"]
    assert back["time"].tolist() == [0.5, 0.75] and back["granule"].tolist() == [3.0, 4.0]


def test_open_table_knows_two_formats(tmp_path) -> None:
    assert isinstance(open_table(tmp_path / "a.csv", ["x"]), Table)
    parquet = open_table(tmp_path / "b.csv", ["x"], "parquet")
    assert isinstance(parquet, ParquetTable) and parquet.path == tmp_path / "b.parquet"
    with pytest.raises(ValueError, match="'csv' or 'parquet'"):
        open_table(tmp_path / "c.csv", ["x"], "json")
    assert table_path(tmp_path, "b") == tmp_path / "b.parquet"
    assert table_path(tmp_path, "a") == tmp_path / "a.csv"
    assert table_path(tmp_path, "none") is None


def test_blocks_hold_what_pa_array_makes_of_each_column(tmp_path) -> None:
    """The columns a frame writes (float64 and strided float64, int64, int32, uint8, booleans
    of lengths that do not fill a byte, strings) go into a block with the type ``pa.array``
    gives them and their values exactly, and a Parquet table reads them back."""
    pa = pytest.importorskip("pyarrow")
    rng = np.random.default_rng(0)
    columns = [VALUES, rng.random((12, 2))[:, 1], np.arange(12), np.arange(12, dtype=np.int32),
               np.arange(12, dtype=np.uint8), rng.random(12) > 0.5,
               np.array(list("abcdefghijkl"))]  # fmt: skip
    names = [f"c{k}" for k in range(len(columns))]
    block = tables._arrow_block(columns, names)
    for name, column in zip(names, columns, strict=True):
        assert block.column(name).type == pa.array(column).type, name
        np.testing.assert_array_equal(np.asarray(block.column(name)), column, err_msg=name)
    for n in (0, 1, 9):
        flags = rng.random(n) > 0.5
        assert tables._arrow_block([flags], ["b"]).column("b").to_pylist() == flags.tolist()
    table = ParquetTable(tmp_path / "p.parquet", names[:6])
    table.write_columns(columns[:6])
    table.close()
    back = read_columns(tmp_path / "p.parquet")
    for name, column in zip(names[:6], columns[:6], strict=True):
        np.testing.assert_array_equal(back[name], column)


def test_writing_a_block_does_not_import_pandas() -> None:
    """``pa.array`` on a numpy array imports pandas where it is installed (0.3 s a process);
    a table block of numbers and booleans does not."""
    code = (
        "import sys, numpy as np; from perga.output.tables import _arrow_block; "
        "_arrow_block([np.zeros(3), np.arange(3), np.ones(3, bool)], ['a', 'b', 'c']); "
        "sys.exit('pandas' in sys.modules)"
    )
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0
