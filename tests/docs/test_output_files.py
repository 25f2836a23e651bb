"""docs/reference/output-files.md names every file a run writes and every column of every table:
a short run of two bundled cases, one rigid (the separator) and one soft with Hertz contacts, a
comb, a feed, damage and an outlet (the bee-bread separator), so that every optional column is
written by one of them."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import pyvista as pv

import perga

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "docs" / "reference" / "output-files.md"
RUNS = {
    "rigid": ("separator.toml", ()),
    "soft": ("bee-bread-separator.toml", ('contact_model.kind="hertz"',)),
}
"""A bundled case and its overrides per run; each runs for DURATION."""
DURATION = 0.002
"""Simulated time of each run, s: a table's header is written at its first frame."""
TICKED = re.compile(r"`([^`]+)`")


def sections(text: str) -> dict[str, str]:
    """The page's ``### `NAME` ...`` sections by NAME (the first name in the heading)."""
    parts = re.split(r"^### ", text, flags=re.M)[1:]
    return {TICKED.search(p.splitlines()[0]).group(1): p for p in parts if "`" in p.split("\n")[0]}


def cell_names(section: str, cell: int) -> set[str]:
    """The backticked names in cell ``cell`` (0-based) of every table row of ``section``."""
    names: set[str] = set()
    for line in section.splitlines():
        cells = line.strip().strip("|").split("|")
        if line.startswith("|") and len(cells) > cell:
            names.update(TICKED.findall(cells[cell]))
    return names


def table_columns(run: Path) -> dict[str, list[str]]:
    """Every table in ``run`` (CSV, Parquet file or dataset) by its CSV name: its columns."""
    tables = {p.name: p.read_text(encoding="utf-8").splitlines()[0].split(",")
              for p in run.glob("*.csv")}  # fmt: skip
    for path in run.glob("*.parquet"):
        schema = pq.ParquetDataset(path).schema if path.is_dir() else pq.read_schema(path)
        tables[f"{path.stem}.csv"] = list(schema.names)
    return tables


def vtk_arrays(run: Path) -> set[str]:
    """The names of the point and cell arrays of every .vtu file in ``run``/vtk, as VTK reads
    them (pyvista)."""
    names: set[str] = set()
    for path in (run / "vtk").glob("*.vtu"):
        mesh = pv.read(path)
        names.update(mesh.point_data.keys(), mesh.cell_data.keys())
    return names


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """The two runs' directories."""
    out = {}
    for name, (case, overrides) in RUNS.items():
        directory = tmp_path_factory.mktemp(name)
        perga.simulate(
            ROOT / "cases" / case,
            directory,
            overrides=[f"solver.duration={DURATION}", *overrides],
            overwrite=True,
        )
        out[name] = directory
    return out


@pytest.fixture(scope="module")
def page() -> dict[str, str]:
    """The page's sections."""
    return sections(PAGE.read_text(encoding="utf-8"))


def test_every_column_of_every_run_table_is_on_the_page(runs, page):
    """Each table's columns are named in its section's first cells; and each column the page
    names for a run's table is one the runs wrote (a column gone from the code goes from the
    page)."""
    written: dict[str, set[str]] = {}
    for run in runs.values():
        for table, columns in table_columns(run).items():
            written.setdefault(table, set()).update(columns)
    missing = {t: sorted(c - cell_names(page.get(t, ""), 0)) for t, c in written.items()}
    assert not {t: c for t, c in missing.items() if c}, f"not on {PAGE.name}: {missing}"
    stale = {t: sorted(cell_names(page[t], 0) - c) for t, c in written.items()}
    assert not {t: c for t, c in stale.items() if c}, f"on {PAGE.name}, written by no run: {stale}"


def test_every_file_of_a_run_and_every_summary_key_is_on_the_page(runs, page):
    """Every file and folder at the top of a run directory is named on the page, and every key
    of summary.json in its section."""
    text = PAGE.read_text(encoding="utf-8")
    named = {name.split("/")[0] for name in TICKED.findall(text)}
    for run in runs.values():
        files = {p.name for p in run.iterdir()}
        assert not files - named, f"files not on {PAGE.name}: {sorted(files - named)}"
        keys = set(json.loads((run / "summary.json").read_text(encoding="utf-8")))
        on_page = cell_names(page["summary.json"], 0)
        assert not keys - on_page, f"summary.json keys not on the page: {sorted(keys - on_page)}"


def test_every_paraview_array_is_on_the_page(runs, page):
    """Every point and cell array of the runs' .vtu files is named in the vtk/ section."""
    arrays = set().union(*(vtk_arrays(run) for run in runs.values()))
    missing = arrays - cell_names(page["vtk/"], 1)
    assert arrays and not missing, f"ParaView arrays not on {PAGE.name}: {sorted(missing)}"
