"""Issue 14, item 4: writing a frame of the granule table row by row in Python (the csv module,
``repr`` per float: ``Table.write``), as columns of arrays (pyarrow's CSV writer:
``Table.write_columns``) and as Parquet (``ParquetTable``, its parts written at close, which
is timed too), side by side on the same frames, interleaved. Prints the medians, the ratios,
the file sizes, the time to read the table back (``read_columns``) and the load.

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

from perga.output.tables import ParquetTable, Table, read_columns

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
            frames = [frame(n, rng) for _ in range(args.frames)]  # distinct, as in a run
            times: dict[str, list[float]] = {"rows": [], "columns": [], "parquet": []}
            paths = {
                "rows": Path(tmp) / "rows.csv",
                "columns": Path(tmp) / "columns.csv",
                "parquet": Path(tmp) / "granules.parquet",
            }
            for _ in range(args.repeats):
                for name, write in (
                    ("rows", rows_path), ("columns", columns_path), ("parquet", columns_path)
                ):  # fmt: skip
                    if name == "parquet":
                        for part in paths[name].glob("*"):
                            part.unlink()
                        table: Table | ParquetTable = ParquetTable(paths[name], COLUMNS)
                    else:
                        table = Table(paths[name], COLUMNS)
                    start = time.perf_counter()
                    for data in frames:
                        write(table, data)
                    table.close()
                    times[name].append((time.perf_counter() - start) / args.frames)
            rows, cols, parquet = (statistics.median(times[k]) for k in paths)
            read = {}
            for name in ("columns", "parquet"):
                start = time.perf_counter()
                back = read_columns(paths[name])
                read[name] = time.perf_counter() - start
                same = all(
                    np.array_equal(back[c], np.concatenate([f[k] for f in frames]).astype(float))
                    for k, c in enumerate(COLUMNS)
                )
                assert same, f"{name}: values read back differ"
            size = {k: sum(f.stat().st_size for f in [p, *p.glob("*")] if f.is_file())
                    for k, p in paths.items()}  # fmt: skip
            print(
                f"{n:>7} granules, ms/frame: rows {rows * 1e3:8.3f}, columns {cols * 1e3:8.3f} "
                f"({cols / rows:.3f} of rows), parquet {parquet * 1e3:8.3f} "
                f"({parquet / cols:.3f} of columns); MB for {args.frames} frames: csv "
                f"{size['columns'] / 1e6:.2f}, parquet {size['parquet'] / 1e6:.2f}; read back "
                f"(same values): csv {read['columns']:.3f} s, parquet {read['parquet']:.3f} s"
            )
    print(f"load {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
