"""A torn table (a row cut short, a value that is not a number) is bad input: the readers name
the file and the row's line, and ``perga report`` / ``perga compare`` say it in one line, exit
2, no traceback."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from perga.cli import main
from perga.output.tables import TableError, read_columns

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    """The bee-bread separator's first 0.015 s (it has impacts by then)."""
    out = tmp_path_factory.mktemp("torn") / "run"
    case = str(ROOT / "cases" / "bee-bread-separator.toml")
    assert main(["run", case, "-o", str(out), "--quiet", "--set", "solver.duration=0.015"]) == 0
    assert len((out / "impacts.csv").read_text().splitlines()) > 3
    return out


def _torn(table: Path, how: str) -> int:
    """Tear the table's third row (line 4 of the file) ``how``: 'cut' (the file ends inside it)
    or 'text' (its second value replaced by a word); the line torn."""
    lines = table.read_bytes().split(b"\r\n")
    if how == "cut":
        table.write_bytes(b"\r\n".join(lines[:3]) + b"\r\n" + lines[3][: len(lines[3]) // 2])
    else:
        values = lines[3].split(b",")
        lines[3] = b",".join([values[0], b"torn", *values[2:]])
        table.write_bytes(b"\r\n".join(lines))
    return 4


@pytest.mark.parametrize("how", ["cut", "text"])
@pytest.mark.parametrize("name", ["granules", "impacts"])
def test_report_and_compare_name_the_torn_file_and_line(run, tmp_path, capsys, name, how):
    torn = tmp_path / "run"
    shutil.copytree(run, torn)
    table = torn / f"{name}.csv"
    line = _torn(table, how)
    width = table.read_text().splitlines()[0].count(",") + 1
    why = f"the header has {width} (a torn row)" if how == "cut" else "'torn' is not a number"
    capsys.readouterr()
    for command in (["report", str(torn)], ["compare", str(torn), "-o", str(tmp_path / "c")]):
        assert main(command) == 2, command
        err = capsys.readouterr().err
        assert err.startswith(f"error: {table}: line {line}: ") and err.count("\n") == 1, err
        assert err.rstrip().endswith(why), err


@pytest.mark.parametrize(
    ("body", "problem"),
    [
        ("0.0,1,2.5\r\n0.1,1,\r\n", "line 3: '' is not a number"),
        ("0.0,1,2.5\r\n\r\n0.1,1\r\n", "line 4: 2 values, the header has 3 (a torn row)"),
        ("0.0,1,2.5\r\n0.1,x1,2\r\n", "line 3: 'x1' is not a number"),
        ("0.0,1\r\n0.1,2\r\n", "rows of 2 values, the header has 3"),
    ],
)
def test_read_columns_names_the_first_bad_line(tmp_path, body, problem):
    table = tmp_path / "t.csv"
    table.write_text("time,id,x\r\n" + body, newline="")
    with pytest.raises(TableError) as caught:
        read_columns(table)
    assert str(caught.value) == f"{table}: {problem}"


def test_read_columns_reads_a_whole_table(tmp_path):
    table = tmp_path / "t.csv"
    table.write_text("time,id,x\r\n0.0,1,2.5\r\n\r\n0.1,2,nan\r\n", newline="")
    columns = read_columns(table)
    assert columns["id"].tolist() == [1.0, 2.0] and columns["x"][0] == 2.5
