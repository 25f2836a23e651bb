"""A stop signal that Python swallows (raised inside a garbage-collector callback or a
``__del__``, where exceptions are printed and ignored) is kept and raised at the next safe
point: a sweep stopped by Ctrl-C while ``distributed``'s gc callback ran once went on to finish
and exit 0."""

from __future__ import annotations

import signal
import sys
from pathlib import Path
from typing import Any

import pytest
from distributed import Client

from perga import stopping
from perga.stopping import StopSignal, raise_swallowed


class _StopsOnDeletion:
    """Raises a stop signal in ``__del__``, as the signal handler does inside a gc callback."""

    def __del__(self) -> None:
        raise StopSignal(signal.SIGTERM)


def _swallow_a_stop() -> None:
    _StopsOnDeletion()  # deleted at once: Python calls sys.unraisablehook


@pytest.fixture
def keeping(monkeypatch: pytest.MonkeyPatch) -> None:
    """The hook :func:`perga.stopping.raise_on_stop_signals` installs, without the handlers."""
    monkeypatch.setattr(sys, "unraisablehook", stopping._keep_swallowed)
    monkeypatch.setattr(stopping, "_swallowed", [])


def test_a_swallowed_stop_is_raised_once(keeping: None) -> None:
    _swallow_a_stop()
    with pytest.raises(StopSignal) as stop:
        raise_swallowed()
    assert stop.value.signum == signal.SIGTERM
    raise_swallowed()  # taken: nothing left to raise


def test_other_swallowed_exceptions_are_reported_as_before(
    keeping: None, capsys: pytest.CaptureFixture[str]
) -> None:
    class Fails:
        def __del__(self) -> None:
            raise ValueError("in __del__")

    Fails()
    raise_swallowed()  # not a stop: nothing raised
    assert "ValueError: in __del__" in capsys.readouterr().err


def _row(key: int) -> dict[str, Any]:
    return {"key": key}


def test_a_study_stops_after_the_row_during_which_a_stop_was_swallowed(
    keeping: None, tmp_path: Path
) -> None:
    """Four jobs on an in-process cluster; a stop swallowed while the first row is handed over:
    ``execute`` raises it after that row and before any other."""
    from perga.studies.executor import execute

    rows: list[dict[str, Any]] = []

    def on_row(row: dict[str, Any]) -> None:
        rows.append(row)
        if len(rows) == 1:
            _swallow_a_stop()

    jobs = [type("Job", (), {"key": k, "directory": tmp_path / f"run-{k}"})() for k in range(4)]
    with (
        Client(processes=False, n_workers=1, dashboard_address=None) as client,
        pytest.raises(StopSignal),
    ):
        execute(client, jobs, on_row, function=lambda job: _row(job.key))  # type: ignore[arg-type]
    assert len(rows) == 1
