"""Calibration data files mutated as a careless user (or a spreadsheet) would (issue 15, item
1): every mutant of ``examples/calibration/measured.csv`` either loads, with every measured
value and standard deviation a finite number and every row's conditions a value the case
accepts, or is refused with :class:`~perga.studies.study_file.StudyError` whose every problem
names the file; never another exception. Seeded, in the default suite."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from perga.studies.calibrate import FitKey, load_data
from perga.studies.study_file import StudyError, check_keys

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "rebound-test.toml"
DATA = (ROOT / "examples" / "calibration" / "measured.csv").read_text(encoding="utf-8")
FITS = [FitKey("contacts.granule-hammer.restitution", 0.4, 0.95)]
ODD = st.sampled_from(
    ["nan", "NaN", "inf", "-inf", "", " ", "abc", "1e400", "-1", "0", "1e-320", "1e300",
     "٣", "0x10", "1,5", '"', "true", "-0", "3.2", "7"]
)  # fmt: skip


@st.composite
def mutants(draw: st.DrawFn) -> bytes:
    rows = [line.split(",") for line in DATA.splitlines()]
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(["cell", "cell", "column", "row", "header", "short row"]))
        i = draw(st.integers(0, len(rows) - 1))
        if kind == "cell" and rows[i]:
            rows[i][draw(st.integers(0, len(rows[i]) - 1))] = draw(ODD)
        elif kind == "column" and rows[0]:
            j = draw(st.integers(0, len(rows[0]) - 1))
            rows = [r[:j] + r[j + 1 :] for r in rows]
        elif kind == "row" and len(rows) > 1:
            del rows[i]
        elif kind == "header" and rows[0]:
            j = draw(st.integers(0, len(rows[0]) - 1))
            rows[0][j] = draw(st.sampled_from([rows[0][-1], "", "x", "first_impact_restitution"]))
        elif kind == "short row" and rows[i]:
            rows[i] = rows[i][:-1]
    data = "\n".join(",".join(r) for r in rows).encode("utf-8")
    if draw(st.integers(0, 9)) == 0:  # now and then bytes: a cut file or a binary flip
        k = draw(st.integers(0, max(len(data) - 1, 0)))
        data = data[:k] + bytes([draw(st.integers(0, 255))]) + data[k + 1 :]
    return data


@settings(
    max_examples=300,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(mutant=mutants())
def test_a_mutated_data_file_loads_or_is_refused_with_its_problems(mutant, tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "measured.csv"
    path.write_bytes(mutant)
    try:
        data = load_data(path, CASE, FITS)
    except StudyError as exc:
        assert exc.problems and all(p.startswith(f"{path}") for p in exc.problems)
        return
    assert data.values.size and all(math.isfinite(v) for v in data.values.ravel())
    assert all(math.isnan(s) or (math.isfinite(s) and s > 0) for s in data.sd.ravel())
    for row in {tuple(sorted(r.items())) for r in data.conditions}:
        assert check_keys(CASE, dict(row), "row") == [], row


def _with(line: int, column: int, value: str) -> str:
    rows = [r.split(",") for r in DATA.splitlines()]
    rows[line - 1][column] = value
    return "\n".join(",".join(r) for r in rows) + "\n"


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        (_with(3, 1, "nan"), "line 3, column first_impact_restitution: not a finite number"),
        (_with(3, 1, "1e400"), "line 3, column first_impact_restitution: not a finite number"),
        (_with(3, 2, "inf"), "line 3, column first_impact_restitution_sd: must be a finite"),
        (_with(3, 2, "0"), "line 3, column first_impact_restitution_sd: must be a finite"),
        (_with(5, 0, "99"), "line 5, condition columns"),
        (_with(5, 0, "9" * 4300), "line 5, condition columns: "),
        (_with(5, 0, "9" * 4301), "line 5, condition columns: an integer of more than 4300"),
        (DATA.replace("0.6,0.726383,0.01,", "0.6,0.726383,", 1), "line 4: 5 cells expected"),
        (_with(1, 4, "first_impact_restitution"), "line 1: every column needs a name"),
    ],
)
def test_each_refusal_names_the_line_and_column(tmp_path, text, problem):
    """Found by the fuzz test: NaN and infinite values and standard deviations were taken,
    a longer row crashed, and only the first row's conditions were checked."""
    path = tmp_path / "measured.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(StudyError) as caught:
        load_data(path, CASE, FITS)
    assert any(p.startswith(f"{path}: {problem}") for p in caught.value.problems), caught.value


@pytest.mark.parametrize(
    "text",
    [_with(3, 1, "0.5"), _with(3, 2, "1e-9"), _with(5, 0, "1.3"), DATA + "\n\n", DATA],
)
def test_the_other_side_of_each_limit_loads(tmp_path, text):
    path = tmp_path / "measured.csv"
    path.write_text(text, encoding="utf-8")
    assert load_data(path, CASE, FITS).values.shape == (7, 2)
