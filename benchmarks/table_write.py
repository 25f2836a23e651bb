"""Issue 14, item 4: writing a frame of the granule table row by row in Python (the csv module,
``repr`` per float: ``Table.write``) against as columns of arrays (pyarrow's CSV writer:
``Table.write_columns``), side by side on the same frames, interleaved. Prints the medians,
the ratio and the load.

    python benchmarks/table_write.py                 # 300 and 10,000 granules, ~20 s
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from perga.output.tables import Table

COLUMNS = ["time", "id", "x", "y", "vx", "vy", "angular_velocity", "speed", "radius", "mass"]


def frame(n: int, rng: np.random.Generator) -> list[np.ndarray]:
    """One frame's columns for ``n`` granules (random state, the table's types)."""
    cols = [np.full(n, 0.0123), np.arange(n, dtype=np.int64)]
    return cols + [rng.normal(size=n) for _ in COLUMNS[2:]]


def rows_path(table: Table, columns: list[np.ndarray]) -> None:
    table.write(zip(*(c.tolist() for c in columns), strict=True))


def columns_path(table: Table, columns: list[np.ndarray]) -> None:
    table.write_columns(columns)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", type=int, nargs="+", default=[300, 10_000])
    p.add_argument("--frames", type=int, default=50, help="frames per timed block")
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args(argv)
    rng = np.random.default_rng(1)
    print(f"load {os.getloadavg()[0]:.2f}; {args.frames} frames a block, {args.repeats} blocks")
    with tempfile.TemporaryDirectory() as tmp:
        for n in args.sizes:
            data = frame(n, rng)
            times: dict[str, list[float]] = {"rows": [], "columns": []}
            for _ in range(args.repeats):
                for name, write in (("rows", rows_path), ("columns", columns_path)):
                    table = Table(Path(tmp) / f"{name}.csv", COLUMNS)
                    start = time.perf_counter()
                    for _ in range(args.frames):
                        write(table, data)
                    times[name].append((time.perf_counter() - start) / args.frames)
                    table.close()
            rows, cols = (statistics.median(times[k]) for k in ("rows", "columns"))
            same = np.array_equal(
                np.loadtxt(Path(tmp) / "rows.csv", delimiter=",", skiprows=1),
                np.loadtxt(Path(tmp) / "columns.csv", delimiter=",", skiprows=1),
            )
            print(
                f"{n:>7} granules: rows {rows * 1e3:8.3f} ms/frame, columns {cols * 1e3:8.3f} "
                f"ms/frame, ratio {cols / rows:.3f}; same values read back: {same}"
            )
    print(f"load {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
