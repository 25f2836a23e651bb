"""CSV tables: a block written as columns reads back to the same float64 bits as one written row
by row, each block is on disk when the call returns, and a wrong shape is refused."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from perga.output.tables import Table

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
