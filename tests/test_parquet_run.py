"""output.tables = "parquet": a complete run's tables as NAME.parquet files holding the CSV run's
values exactly, read by every reader of a run; a run stopped before its end keeps its CSV
tables and, resumed, ends as Parquet."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from perga.case import load_case
from perga.cli import main
from perga.output.tables import read_columns, table_path
from perga.run.directory import prepare_directory
from perga.run.loop import run_case
from perga.stats import load_run
from perga.stats.metrics import MetricUnavailableError, evaluate
from perga.stats.tables import TABLES
from perga.studies.run_report import PROCESS_METRICS

ROOT = Path(__file__).resolve().parents[1]
SETS = [
    "solver.duration=0.04",
    "output.every=0.001",
    "output.checkpoint_every=0.01",
    'output.record=["granules", "hammers", "impacts", "energy"]',
]
"""The single-granule case to past its first impact (about 22 ms): every table has rows."""


def _run(out: Path, tables: str, *extra: str) -> Path:
    sets = [a for s in [*SETS, f'output.tables="{tables}"', *extra] for a in ("--set", s)]
    case = str(ROOT / "cases" / "single-granule.toml")
    assert main(["run", case, "-o", str(out), "--quiet", *sets]) == 0
    return out


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """The case run with CSV tables and with Parquet tables."""
    root = tmp_path_factory.mktemp("tables")
    return {form: _run(root / form, form) for form in ("csv", "parquet")}


def _tables(run: Path) -> dict[str, dict[str, np.ndarray]]:
    """Every table of the run, by name, whichever its form."""
    names = {p.stem for p in run.iterdir() if p.suffix in (".csv", ".parquet")}
    return {name: read_columns(table_path(run, name)) for name in sorted(names)}


def test_parquet_tables_hold_the_csv_values_exactly(runs) -> None:
    """Each table of the CSV run is a NAME.parquet file (no CSV, no temporary left) with the
    same columns in the same order and the same float64 values, NaN where NaN; ids and counts
    are int64, the rest float64."""
    csv, parquet = _tables(runs["csv"]), _tables(runs["parquet"])
    assert set(csv) == {"granules", "hammers", "impacts", "contacts", "energy"}
    assert sorted(p.name for p in runs["parquet"].iterdir() if p.is_file()) == sorted(
        [f"{name}.parquet" for name in csv] + ["case.toml", "scene.json", "summary.json"]
    )
    for name, columns in csv.items():
        assert list(parquet[name]) == list(columns), name
        assert len(next(iter(columns.values()))) > 0, name
        for column, values in columns.items():
            assert np.array_equal(parquet[name][column], values, equal_nan=True), (name, column)
    schema = pq.read_schema(runs["parquet"] / "impacts.parquet")
    assert str(schema.field("granule").type) == "int64"
    assert str(schema.field("held").type) == "int64"
    assert str(schema.field("time").type) == "double"


def test_every_reader_takes_a_parquet_run(runs, tmp_path, capsys) -> None:
    """load_run, perga metrics, report, compare, render (frame, trajectories, process) and
    --from read the Parquet run as the CSV run."""
    a, b = load_run(runs["csv"]), load_run(runs["parquet"])
    for name in TABLES:
        assert getattr(a, name).keys() == getattr(b, name).keys(), name
        for column, values in getattr(a, name).items():
            assert np.array_equal(getattr(b, name)[column], values, equal_nan=True)
    printed = {}
    for form, run in runs.items():
        capsys.readouterr()
        assert main(["metrics", str(run)]) == 0
        printed[form] = capsys.readouterr().out
    assert printed["csv"] == printed["parquet"]
    assert printed["parquet"].count(" = ") >= 10  # the metrics of the impact and the path
    run = str(runs["parquet"])
    assert main(["report", run, "-o", str(tmp_path / "report")]) == 0
    assert main(["compare", run, "-o", str(tmp_path / "compare")]) == 0
    for view in ([], ["--trajectories"], ["--process"]):
        assert main(["render", run, *view, "-o", str(tmp_path / "view.png")]) == 0
    case = str(ROOT / "cases" / "single-granule.toml")
    start = ["run", case, "--from", f"{run}:0.03", "-o", str(tmp_path / "from"), "--quiet"]
    assert main([*start, "--set", "solver.duration=0.002"]) == 0


def test_a_stopped_parquet_run_keeps_csv_and_resumes_to_parquet(runs, tmp_path) -> None:
    """Stopped at 25 ms (a stop request raised from the progress report), the run keeps its
    tables as CSV, which --resume appends to; it then ends with the Parquet tables of the run
    that never stopped, value for value."""
    out, case_path = tmp_path / "stopped", ROOT / "cases" / "single-granule.toml"
    prepare_directory(out, overwrite=False)
    case = load_case(case_path, overrides=[*SETS, 'output.tables="parquet"'])

    def stop(t: float, _duration: float, _steps: int) -> None:
        if t >= 0.025:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_case(case, case_path, out, progress=stop)
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    assert (out / "granules.csv").exists() and not (out / "granules.parquet").exists()
    assert main(["run", "--resume", str(out), "--quiet"]) == 0
    assert not list(out.glob("*.csv"))
    whole, resumed = _tables(runs["parquet"]), _tables(out)
    assert whole.keys() == resumed.keys()
    for name, columns in whole.items():
        for column, values in columns.items():
            assert np.array_equal(resumed[name][column], values, equal_nan=True), (name, column)


def test_the_process_metrics_of_a_parquet_run_are_the_csv_runs(tmp_path) -> None:
    """The bee-bread separator (comb, feed, damage, screen) for 0.05 s, CSV and Parquet: every
    process metric, outflow and releases included, is the same number (or the same reason it
    is unavailable: nothing has left through the screen yet) from either."""
    case = str(ROOT / "cases" / "bee-bread-separator.toml")
    values = {}
    for form in ("csv", "parquet"):
        sets = ["solver.duration=0.05", f'output.tables="{form}"', "output.checkpoint_every=0"]
        overrides = [a for s in sets for a in ("--set", s)]
        assert main(["run", case, "-o", str(tmp_path / form), "--quiet", *overrides]) == 0
        run = load_run(tmp_path / form)
        values[form] = [_value_or_reason(run, name) for name in PROCESS_METRICS]
    assert (tmp_path / "parquet" / "outflow.parquet").exists()
    assert values["parquet"] == values["csv"]
    assert isinstance(values["csv"][PROCESS_METRICS.index("throughput")], float)


def _value_or_reason(run, name: str) -> float | str:
    """Metric ``name`` of ``run``, or why the run cannot give it."""
    try:
        return evaluate(run, name)
    except MetricUnavailableError as exc:
        return str(exc)
