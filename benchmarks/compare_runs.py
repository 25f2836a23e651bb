"""Two run directories' tables compared column by column (issue 14's "results unchanged"):
per table, the largest |difference| relative to the column's largest |value|, the column it is
in, and for the granule table the first frame that differs at all.

    python benchmarks/compare_runs.py RUN_A RUN_B
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from perga.output.tables import read_columns, table_path

TABLES = ("granules", "hammers", "impacts", "energy", "releases", "outflow")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a", type=Path)
    parser.add_argument("b", type=Path)
    args = parser.parse_args()
    for name in TABLES:
        pa, pb = table_path(args.a, name), table_path(args.b, name)
        if pa is None or pb is None:
            continue
        a, b = read_columns(pa), read_columns(pb)
        if list(a) != list(b) or len(a["time"]) != len(b["time"]):
            print(f"{name:>9}: {len(a['time'])} against {len(b['time'])} rows (or other columns)")
            continue
        worst, where = 0.0, "-"
        for column in a:
            ok = np.isfinite(a[column]) & np.isfinite(b[column])
            if not ok.any():
                continue
            scale = max(float(np.abs(a[column][ok]).max()), 1e-300)
            d = float(np.abs(a[column][ok] - b[column][ok]).max()) / scale
            if d > worst:
                worst, where = d, column
        rows = len(a["time"])
        line = f"{name:>9}: {rows} rows, largest |difference| / |column| {worst:.2e} ({where})"
        if name == "granules" and worst > 0:
            differs = np.flatnonzero((a["x"] != b["x"]) | (a["y"] != b["y"]))
            if differs.size:
                line += f"; first position difference at t = {a['time'][differs[0]]:.6g} s"
        print(line)


if __name__ == "__main__":
    main()
