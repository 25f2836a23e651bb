"""The soft kernel's threads: one unless asked or worth it, never more than the free cores, and
what a run used in its summary."""

from __future__ import annotations

import json
from pathlib import Path

import numba
import pytest

from perga.cli import main
from perga.contact.soft import threads as t

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture
def numba_two(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(numba, "get_num_threads", lambda: 2)


@pytest.mark.parametrize(
    ("granules", "free", "used"),
    [(t.THREADED_FROM - 1, 2, 1), (t.THREADED_FROM, 2, 2), (t.THREADED_FROM, 1, 1)],
)
def test_auto_is_one_thread_unless_large_and_two_cores_free(numba_two, granules, free, used):
    assert t.kernel_threads(None, granules, free) == used


@pytest.mark.parametrize(("asked", "free", "used"), [(2, 2, 2), (2, 1, 1), (1, 2, 1), (8, 2, 2)])
def test_asked_threads_never_exceed_the_free_cores_or_numba(numba_two, asked, free, used):
    assert t.kernel_threads(asked, 10, free) == used


def test_a_dask_worker_limit_of_one_holds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(numba, "get_num_threads", lambda: 1)
    assert t.kernel_threads(None, 100_000, 8) == 1
    assert t.kernel_threads(4, 10, 8) == 1


def test_free_cores_is_cores_minus_load(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(t.os, "sched_getaffinity", lambda _: {0, 1}, raising=False)
    for load, free in ((0.2, 2), (0.6, 1), (1.4, 1), (3.0, 1)):
        monkeypatch.setattr(t.os, "getloadavg", lambda load=load: (load, 0.0, 0.0))
        assert t.free_cores() == free


@pytest.mark.parametrize(("asked", "free", "warned"), [(2, 1, True), (1, 1, False)])
def test_the_summary_says_how_many_threads_and_warns_when_fewer(
    tmp_path, monkeypatch: pytest.MonkeyPatch, asked, free, warned
):
    monkeypatch.setattr("perga.contact.soft.model.free_cores", lambda: free)
    out = tmp_path / "run"
    case = ROOT / "cases" / "soft-single-granule.toml"
    args = ["run", str(case), "-o", str(out), "--quiet", "--set", f"solver.threads={asked}",
            "--set", "solver.duration=0.001"]  # fmt: skip
    assert main(args) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["threads"] == 1
    assert any("solver.threads = 2 asked, 1 used" in w for w in summary["warnings"]) == warned


@pytest.mark.parametrize(
    ("value", "ok"), [("1", True), ("256", True), ("0", False), ("257", False)]
)
def test_solver_threads_range(tmp_path, capsys, value, ok):
    case = ROOT / "cases" / "soft-single-granule.toml"
    args = ["run", str(case), "-o", str(tmp_path / "run"), "--quiet",
            "--set", f"solver.threads={value}", "--set", "solver.duration=0.0005"]  # fmt: skip
    assert main(args) == (0 if ok else 2)
    if not ok:
        assert "solver.threads" in capsys.readouterr().err
