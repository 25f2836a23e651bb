"""The runs of ``perga compare --paper`` as override sets on the bundled cases: the same case
data as the text edits they replaced, run as study jobs (that they run on the executor, and
that finished ones are found by key, is in test_compare.py, on its report's runs).

paper_runs_text_edits.json was computed once from the text edits of the case files that the
override sets replaced (whole lines of the TOML swapped, a ``record`` line added where none
was): for each run, in order, the SHA-256 of its case data as JSON with sorted keys, and the
values the edits set.
"""

from __future__ import annotations

import hashlib
import json
import math
from pathlib import Path
from typing import Any

import pytest

from perga.case.load import overridden, read_case_data
from perga.case.schema import Case
from perga.cli import main
from perga.studies.jobs import failed_row
from perga.studies.paper_runs import PaperRun, paper_job, paper_jobs

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"
TEXT_EDITS = json.loads((Path(__file__).parent / "paper_runs_text_edits.json").read_text())


def _data(run: PaperRun, overrides: tuple[str, ...] | None = None) -> dict[str, Any]:
    path = CASES / run.case
    return overridden(read_case_data(path), run.overrides if overrides is None else overrides, path)


def _digest(data: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def _at(data: dict[str, Any], key: str) -> Any:
    """The value at a dotted key (``contacts[0].friction``), None where there is none."""
    node: Any = data
    for part in key.replace("[0]", ".0").split("."):
        if part == "0":
            node = node[0]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            return None
    return node


def _set(data: dict[str, Any], key: str, value: Any) -> None:
    """Set the value at a dotted key that exists (:func:`_at`)."""
    *path, last = key.replace("[0]", ".0").split(".")
    node: Any = data
    for part in path:
        node = node[0] if part == "0" else node[part]
    node[last] = value


def test_the_override_sets_give_the_case_data_of_the_text_edits() -> None:
    """Every run, in the same order: the values the edits set (exact, but for a float computed
    by integrating an ODE, the blade's exit time in solver.duration: to 1e-9 relative, ten
    times BladeSlide.integrate's rtol of 1e-10; its digits below that are scipy's and numpy's,
    0.09667955078947306 against 0.09667955077830616, 1.2e-10 apart, with scipy 1.17), then
    the whole case data with those floats as the edits had them (its digest)."""
    runs = paper_jobs(CASES)
    assert [r.name for r in runs] == list(TEXT_EDITS)
    for run in runs:
        data, old = _data(run), TEXT_EDITS[run.name]
        for key, value in old.items():
            if key == "sha256":
                continue
            now = _at(data, key)
            if key == "solver.duration" and run.name.startswith("blade-"):
                assert math.isclose(now, value, rel_tol=1e-9, abs_tol=0.0), (run.name, now)
                _set(data, key, value)
            else:
                assert now == value, (run.name, key)
        assert _digest(data) == old["sha256"], run.name


def test_the_digest_sees_one_value_left_out() -> None:
    """The blade runs set both frictions (the face's and the floor's), as the old edit of every
    ``friction = 0.35`` line did: without the floor's, the data differ."""
    run = next(r for r in paper_jobs(CASES) if r.name == "blade-w2-f0.8")
    face_only = tuple(o for o in run.overrides if not o.startswith("effects.floor_friction"))
    assert len(face_only) == len(run.overrides) - 1
    assert _digest(_data(run, face_only)) != TEXT_EDITS[run.name]["sha256"]


def test_the_jobs_seed_is_the_case_files_own() -> None:
    """A job adds ``solver.seed``: the schema's default, so the validated case is the one of
    the override set alone."""
    for run in paper_jobs(CASES):
        job = paper_job(run, CASES, Path("work"))
        assert job.overrides[: len(run.overrides)] == run.overrides
        assert any(o.startswith("solver.seed=") for o in job.overrides)
        with_seed = Case.model_validate(_data(run, job.overrides)).model_dump()
        assert with_seed == Case.model_validate(_data(run)).model_dump(), run.name


def test_a_paper_run_that_failed_is_named_and_exits_1(tmp_path: Path, monkeypatch, capsys) -> None:
    """The executor's row of a failed run (here hinged-M5g's, made up): exit 1, the run named
    with its directory and reason, no report."""

    def one_fails(jobs, on_row, **_) -> int:
        for i, job in enumerate(jobs):
            reason = "RunStoppedError: the granule left the chamber"
            on_row(failed_row(job, reason) if i == 5 else failed_row(job, "") | {"status": "ok"})
        return len(jobs)

    monkeypatch.setattr("perga.studies.paper_runs.run_missing", one_fails)
    out = tmp_path / "paper"
    assert main(["compare", "--paper", "-o", str(out), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "error: the paper run hinged-M5g (" in err
    assert "): RunStoppedError: the granule left the chamber" in err
    assert err.count("error: the paper run") == 1 and "--retry-failed" in err
    assert not (out / "report.md").exists()


@pytest.mark.parametrize(
    ("options", "cluster"),
    [
        ([], {"scheduler": None, "workers": None, "retry_failed": False}),
        (["--workers", "1", "--retry-failed"], {"scheduler": None, "workers": 1,
                                                "retry_failed": True}),
        (["--scheduler", "tcp://127.0.0.1:8786"], {"scheduler": "tcp://127.0.0.1:8786",
                                                   "workers": None, "retry_failed": False}),
    ],
)  # fmt: skip
def test_compare_takes_the_options_of_runs_on_dask(
    options: list[str], cluster: dict[str, Any], tmp_path: Path, monkeypatch
) -> None:
    """--workers, --scheduler and --retry-failed reach the paper study as they reach a sweep."""
    given: dict[str, Any] = {}

    def study(cases: Path, work: Path, **kwargs: Any) -> list:
        given.update(kwargs, work=work)
        raise KeyboardInterrupt  # stop here: nothing to analyse

    monkeypatch.setattr("perga.studies.paper_runs.run_paper_study", study)
    out = tmp_path / "paper"
    assert main(["compare", "--paper", "-o", str(out), "--quiet", *options]) == 130
    assert {k: given[k] for k in cluster} == cluster
    assert given["work"] == out / "runs"
