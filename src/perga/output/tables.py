"""Run tables: CSV tables that stay readable when a run stops midway (the header is written
first, every block of rows goes to the file in one write as soon as it is made, and a write that
fails, as on a full disk, is cut back so that the file ends on a whole row), each written as one
Parquet file at the end of a run that asks for it (:meth:`Table.write_parquet`), and, for large
runs, the granule table as a Parquet dataset while the run goes (:class:`ParquetTable`);
:func:`read_run_table` reads a run's table whichever form it has.

Rows of Python values go through the ``csv`` module (floats as ``repr``); a block given as
columns of arrays (``write_columns``: a frame of granules) goes through pyarrow's CSV writer,
which formats the whole block in C++. Both write the shortest text that reads back to the same
float64 (Arrow writes ``1`` and ``0.00001`` where ``repr`` writes ``1.0`` and ``1e-05``).
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import TracebackType
from typing import Self

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from perga.output.files import reopen_at, write_all

_NO_HEADER = pacsv.WriteOptions(include_header=False, eol="\r\n")  # the csv module's line end


def _arrow_block(columns: Sequence[np.ndarray], names: Sequence[str]) -> pa.Table:
    """The columns (numpy arrays of one length) as an Arrow table named ``names``."""
    return pa.Table.from_arrays([_arrow_array(np.asarray(c)) for c in columns], names=list(names))


def _arrow_array(values: np.ndarray) -> pa.Array:
    """``values`` as an Arrow array: fixed-width numbers as a view of their memory, booleans
    bit-packed, anything else through ``pa.array``, which on a numpy array imports pandas where
    it is installed (0.3 s a process, docs/dev/performance.md)."""
    if values.ndim == 1 and values.dtype == np.bool_:
        bits = pa.py_buffer(np.packbits(values, bitorder="little"))
        return pa.Array.from_buffers(pa.bool_(), len(values), [None, bits])
    if values.ndim == 1 and values.dtype.kind in "iuf" and values.dtype.isnative:
        values = np.ascontiguousarray(values)
        dtype = pa.from_numpy_dtype(values.dtype)
        return pa.Array.from_buffers(dtype, len(values), [None, pa.py_buffer(values)])
    return pa.array(values)


class _Closable:
    """A table used as a context manager: closed on leaving the block."""

    def close(self) -> None:
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class Table(_Closable):
    """One CSV file with a fixed header; rows are appended in blocks, each block whole or not at
    all: it goes to the file in one unbuffered write, and a write that fails (a full disk, a
    file-size limit) cuts the file back to the end of the last whole block before the error is
    raised, so the file always ends on a whole row."""

    def __init__(self, path: Path, columns: Sequence[str], integers: Iterable[str] = ()) -> None:
        self.path = path
        self.columns = tuple(columns)
        self.integers = frozenset(integers)
        """The columns of whole numbers (int64 in the Parquet form; the rest float64)."""
        if not self.integers <= set(self.columns):
            raise ValueError(f"{path.name}: integer columns {sorted(self.integers)} not all in "
                             f"the header {self.columns}")  # fmt: skip
        self._fd: int | None = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        self._size = 0
        """Bytes of whole blocks in the file."""
        self.rows = 0
        self._append(_csv_lines([self.columns]))

    def __getstate__(self) -> dict[str, object]:
        """The table as it stands (a checkpoint): its path, header, size and rows."""
        return {
            "path": self.path, "columns": self.columns, "integers": self.integers,
            "_size": self._size, "rows": self.rows,
        }  # fmt: skip

    def __setstate__(self, state: dict[str, object]) -> None:
        """Go on appending to the file as it stood at the checkpoint: rows written after it
        are cut off (OSError if the file is missing or shorter than then), and a Parquet form
        written by an end that did not complete is removed."""
        self.__dict__.update(state)
        self._fd = reopen_at(self.path, self._size)
        if (stale := self.path.with_suffix(".parquet")).is_file():
            stale.unlink()

    def write(self, rows: Iterable[Sequence[object]]) -> None:
        """Append rows (each as long as the header)."""
        block = []
        for row in rows:
            if len(row) != len(self.columns):
                raise ValueError(
                    f"{self.path.name}: row of {len(row)} values, header has {len(self.columns)}"
                )
            # repr of a Python float round-trips; numpy scalars (float subclasses) would write
            # "np.float64(...)"
            block.append([repr(float(v)) if isinstance(v, float) else v for v in row])
        if block:
            self._append(_csv_lines(block))
            self.rows += len(block)

    def write_columns(self, columns: Sequence[np.ndarray]) -> None:
        """Append a block given as one array per column (all of one length)."""
        if len(columns) != len(self.columns):
            raise ValueError(
                f"{self.path.name}: {len(columns)} columns given, header has {len(self.columns)}"
            )
        block = _arrow_block(columns, self.columns)
        text = pa.BufferOutputStream()
        pacsv.write_csv(block, text, _NO_HEADER)
        self._append(text.getvalue().to_pybytes())
        self.rows += block.num_rows

    def _append(self, data: bytes) -> None:
        """Write ``data`` at the end of the file, whole, or cut the file back and raise."""
        if self._fd is None:
            raise ValueError(f"{self.path.name} is closed")
        try:
            write_all(self._fd, data)
        except OSError:
            os.ftruncate(self._fd, self._size)
            raise
        self._size += len(data)

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None

    def write_parquet(self) -> None:
        """Close the table and write it beside its CSV as ``NAME.parquet``, one file (zstd;
        :attr:`integers` int64, the other columns float64: the CSV's values exactly), read and
        written in parts of :data:`PART_ROWS` rows (one row group each), atomically (a
        temporary file renamed; on an error it is removed and the CSV kept). The CSV stays:
        :func:`drop_converted` removes it once the run's end is recorded. Nothing to do once the
        CSV is gone (idempotent)."""
        self.close()
        if not self.path.exists():
            return
        types = {c: pa.int64() if c in self.integers else pa.float64() for c in self.columns}
        convert = pacsv.ConvertOptions(column_types=types, null_values=[])  # "nan" is NaN
        target = self.path.with_suffix(".parquet")
        temporary = target.with_name(f".{target.name}.tmp")
        try:
            with (
                pacsv.open_csv(self.path, convert_options=convert) as reader,
                pq.ParquetWriter(temporary, reader.schema, compression="zstd") as writer,
            ):
                part: list[pa.RecordBatch] = []
                for batch in reader:
                    part.append(batch)
                    if sum(b.num_rows for b in part) >= PART_ROWS:
                        writer.write_table(pa.Table.from_batches(part))
                        part = []
                writer.write_table(pa.Table.from_batches(part, schema=reader.schema))
            temporary.replace(target)
        except BaseException:
            temporary.unlink(missing_ok=True)
            raise


def drop_converted(directory: Path) -> None:
    """Remove each ``NAME.csv`` of the run ``directory`` that has its Parquet form, the file
    ``NAME.parquet`` (:meth:`Table.write_parquet`), once the run's end is recorded."""
    for csv_path in directory.glob("*.csv"):
        if csv_path.with_suffix(".parquet").is_file():
            csv_path.unlink()


def _csv_lines(rows: Iterable[Sequence[object]]) -> bytes:
    """``rows`` as CSV text (the csv module's quoting and line ends), UTF-8."""
    text = io.StringIO()
    csv.writer(text).writerows(rows)
    return text.getvalue().encode("utf-8")


PART_ROWS = 1 << 20
"""Rows of a Parquet part: a part is written once it holds this many (and at close)."""


class ParquetTable(_Closable):
    """A table as a Parquet dataset, the directory ``path`` (``NAME.parquet/``) of parts
    ``part-NNNNN.parquet`` that pyarrow, DuckDB, Polars and pandas read as one table. Blocks are
    kept in memory until they make :data:`PART_ROWS` rows, then written as one part, atomically
    (a temporary file renamed), and the rest at :meth:`close`: parts on disk are always
    complete, and what a killed process had not written yet is lost (at most one part). Chosen
    over one Parquet file (unreadable until its footer is written at the end) and over CSV for
    size and speed (docs/dev/performance.md)."""

    def __init__(self, path: Path, columns: Sequence[str]) -> None:
        self.path = path
        self.columns = tuple(columns)
        path.mkdir(parents=True, exist_ok=True)
        self.rows = 0
        self._blocks: list[pa.Table] = []
        self._pending = 0
        self._parts = 0
        self._closed = False

    def write(self, rows: Iterable[Sequence[object]]) -> None:
        """Append rows (each as long as the header)."""
        rows = list(rows)
        if rows:
            self.write_columns([np.asarray(column) for column in zip(*rows, strict=True)])

    def write_columns(self, columns: Sequence[np.ndarray]) -> None:
        """Append a block given as one array per column (all of one length)."""
        if len(columns) != len(self.columns):
            raise ValueError(
                f"{self.path.name}: {len(columns)} columns given, header has {len(self.columns)}"
            )
        block = _arrow_block(columns, self.columns)
        self._blocks.append(block)
        self._pending += block.num_rows
        self.rows += block.num_rows
        if self._pending >= PART_ROWS:
            self._write_part()

    def __setstate__(self, state: dict[str, object]) -> None:
        """Go on from a checkpoint: parts written after it are removed (the rows they hold
        come again from the blocks kept in memory and the steps that follow)."""
        self.__dict__.update(state)
        for part in self.path.glob("part-*.parquet"):
            if int(part.stem.removeprefix("part-")) >= self._parts:
                part.unlink()

    def _write_part(self) -> None:
        if not self._blocks:
            return
        part = self.path / f"part-{self._parts:05d}.parquet"
        temporary = self.path / f".{part.name}.tmp"  # readers skip names starting with "."
        pq.write_table(pa.concat_tables(self._blocks), temporary)
        temporary.replace(part)
        self._parts += 1
        self._blocks, self._pending = [], 0

    def close(self) -> None:
        """Write what is held in memory (idempotent)."""
        if not self._closed:
            self._closed = True
            self._write_part()

    def write_parquet(self) -> None:
        """Close the table: it is Parquet already (:meth:`Table.write_parquet`)."""
        self.close()


def open_table(
    path: Path, columns: Sequence[str], table_format: str = "csv", integers: Iterable[str] = ()
) -> Table | ParquetTable:
    """The table ``path`` (``NAME.csv``) in ``table_format``: 'csv' (:class:`Table`, whole
    numbers in the columns ``integers``) or 'parquet' (:class:`ParquetTable` at
    ``NAME.parquet``, each column of its arrays' type)."""
    if table_format == "parquet":
        return ParquetTable(path.with_suffix(".parquet"), columns)
    if table_format != "csv":
        raise ValueError(f"table format must be 'csv' or 'parquet' (got {table_format!r})")
    return Table(path, columns, integers)


def table_path(directory: Path, name: str) -> Path | None:
    """Run table ``name`` ('granules', 'impacts', ...) in ``directory``: ``NAME.parquet`` or
    ``NAME.csv``, None when the run has neither."""
    for path in (directory / f"{name}.parquet", directory / f"{name}.csv"):
        if path.exists():
            return path
    return None


def read_run_table(directory: Path, name: str) -> dict[str, np.ndarray]:
    """The table ``name`` ('granules', 'impacts', ...) of the run ``directory`` as {column:
    float64 array}, whichever form it has (:func:`table_path`: ``NAME.parquet``, a file or a
    dataset, else ``NAME.csv``); FileNotFoundError naming the table when it has neither."""
    path = table_path(directory, name)
    if path is None:
        raise FileNotFoundError(
            f"{directory / name}.csv: missing, nor {name}.parquet (record it with output.record)"
        )
    return read_columns(path)


class TableError(ValueError):
    """A run table that cannot be read (torn, damaged, not a table): the message names the
    file and, in a CSV table, the first bad row by its line number."""


def read_columns(path: Path) -> dict[str, np.ndarray]:
    """A run table (a CSV file with a header row, or a Parquet dataset) as {column: float64
    array}; empty columns when it has no rows. TableError naming the file (and a CSV's first
    bad line) when it cannot be read."""
    if path.suffix == ".parquet":
        try:
            table = pq.read_table(path)
        except pa.ArrowException as exc:
            raise TableError(f"{path}: not a readable Parquet table ({exc})") from None
        return {name: table.column(name).to_numpy().astype(float) for name in table.column_names}
    try:
        with path.open(encoding="utf-8") as stream:
            header = stream.readline().strip().split(",")
            body = stream.read()
    except UnicodeDecodeError:
        raise TableError(f"{path}: not a CSV table (not UTF-8 text)") from None
    if not body.strip():
        return {name: np.empty(0) for name in header}
    lines = body.splitlines()
    try:
        data = np.loadtxt(lines, delimiter=",", ndmin=2)
    except ValueError as exc:
        raise TableError(f"{path}: {_first_bad_row(lines, len(header)) or exc}") from None
    if data.shape[1] != len(header):
        raise TableError(f"{path}: rows of {data.shape[1]} values, the header has {len(header)}")
    return {name: data[:, i] for i, name in enumerate(header)}


def _first_bad_row(lines: Sequence[str], width: int) -> str:
    """The first of a CSV table's rows (``lines``, those after its header) that is not
    ``width`` numbers, in words with its line number in the file; "" if none is."""
    for number, line in enumerate(lines, start=2):
        values = line.split(",")
        if not line.strip():
            continue
        if len(values) != width:
            return f"line {number}: {len(values)} values, the header has {width} (a torn row)"
        for value in values:
            try:
                float(value)
            except ValueError:
                return f"line {number}: {value.strip()!r} is not a number"
    return ""
