"""Case files: every bundled case validates, every bad case fails with its expected messages."""

from pathlib import Path

import pytest

from perga.case import CaseError, load_case
from perga.cli import main
from perga.model.compile import check, compile_case

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = sorted((ROOT / "cases").glob("*.toml"))
BAD = sorted((ROOT / "tests" / "cases" / "bad").glob("*.toml"))


@pytest.mark.parametrize("path", BUNDLED, ids=lambda p: p.name)
def test_bundled_case_validates(path):
    case = load_case(path)
    check(case)
    if case.chamber is not None:
        assert 0 < compile_case(case).granule_dt <= 0.01


@pytest.mark.parametrize("path", BAD, ids=lambda p: p.name)
def test_bad_case_fails_with_every_expected_message(path, capsys):
    expected = [
        line.removeprefix("# expect: ")
        for line in path.read_text().splitlines()
        if line.startswith("# expect: ")
    ]
    assert expected, f"{path.name} declares no '# expect:' line"
    with pytest.raises(CaseError) as info:
        check(load_case(path))
    for message in expected:
        assert any(message in problem for problem in info.value.problems), (message, info.value)
    assert all(problem.startswith(f"{path}: ") for problem in info.value.problems)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert err.count("error: ") == len(info.value.problems)


def test_validate_lists_problems_of_several_files_and_exits_2(capsys):
    assert main(["validate", str(BUNDLED[0]), str(BAD[0]), str(BAD[1])]) == 2
    captured = capsys.readouterr()
    assert f"ok: {BUNDLED[0]}" in captured.out
    assert str(BAD[0]) in captured.err and str(BAD[1]) in captured.err


def test_schema_prints_json_schema(capsys):
    import json

    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema["additionalProperties"] is False
    assert "rotor" in schema["required"]
