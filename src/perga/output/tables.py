"""CSV tables that stay readable when a run stops midway: the header is written first and every
block of rows is flushed to disk as soon as it is written.

Rows of Python values go through the ``csv`` module (floats as ``repr``); a block given as
columns of arrays (``write_columns``: a frame of granules) goes through pyarrow's CSV writer,
which formats the whole block in C++. Both write the shortest text that reads back to the same
float64 (Arrow writes ``1`` and ``0.00001`` where ``repr`` writes ``1.0`` and ``1e-05``).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import TracebackType

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv

_NO_HEADER = pacsv.WriteOptions(include_header=False)


class Table:
    """One CSV file with a fixed header; rows are written and flushed in blocks."""

    def __init__(self, path: Path, columns: Sequence[str]) -> None:
        self.path = path
        self.columns = tuple(columns)
        self._file = path.open("w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._file)
        self._writer.writerow(self.columns)
        self._file.flush()
        self.rows = 0

    def write(self, rows: Iterable[Sequence[object]]) -> None:
        """Append rows (each as long as the header) and flush them to disk."""
        for row in rows:
            if len(row) != len(self.columns):
                raise ValueError(
                    f"{self.path.name}: row of {len(row)} values, header has {len(self.columns)}"
                )
            # repr of a Python float round-trips; numpy scalars (float subclasses) would write
            # "np.float64(...)"
            self._writer.writerow([repr(float(v)) if isinstance(v, float) else v for v in row])
            self.rows += 1
        self._file.flush()

    def write_columns(self, columns: Sequence[np.ndarray]) -> None:
        """Append a block given as one array per column (all of one length) and flush it."""
        if len(columns) != len(self.columns):
            raise ValueError(
                f"{self.path.name}: {len(columns)} columns given, header has {len(self.columns)}"
            )
        block = pa.table([pa.array(np.asarray(c)) for c in columns], names=list(self.columns))
        text = io.BytesIO()
        pacsv.write_csv(block, text, _NO_HEADER)
        self._file.write(text.getvalue().decode("utf-8").replace("\n", "\r\n"))
        self.rows += block.num_rows
        self._file.flush()

    def close(self) -> None:
        """Close the file (idempotent)."""
        if not self._file.closed:
            self._file.close()

    def __enter__(self) -> Table:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
