"""CSV tables that stay readable when a run stops midway: the header is written first and every
block of rows is flushed to disk as soon as it is written."""

from __future__ import annotations

import csv
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import TracebackType


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
