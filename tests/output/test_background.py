"""perga.output.background: the ParaView writer on a thread of its own writes the bytes the
in-line writer writes, in order, raises its failures in the run's thread, and is whole at a
checkpoint."""

from __future__ import annotations

import pickle
import threading
import time
from pathlib import Path

import pytest

import perga.run.loop as loop
from perga.model.records import Events
from perga.output.background import BackgroundRecorder
from perga.output.vtk import VtkRecorder
from perga.run import simulate

CASES = Path(__file__).parents[2] / "cases"


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_the_thread_writes_the_bytes_of_the_writer_in_line(tmp_path, monkeypatch):
    """0.05 s of the bee-bread separator (15 impacts, granules fed and released): every
    ParaView file equal byte for byte to a run whose writer is called in line (the frames'
    impact counts are those at the frame, though the thread writes it later)."""
    overrides = ["solver.duration=0.05"]
    case = CASES / "bee-bread-separator.toml"
    record = VtkRecorder.record

    def late(self, frame, events):  # the thread two frames behind: the run goes on meanwhile
        time.sleep(0.06)
        record(self, frame, events)

    with monkeypatch.context() as patch:
        patch.setattr(VtkRecorder, "record", late)
        simulate(case, tmp_path / "thread", overrides=overrides)
    monkeypatch.setattr(loop, "BackgroundRecorder", lambda recorder: recorder)
    simulate(case, tmp_path / "in-line", overrides=overrides)
    threaded, in_line = (_files(tmp_path / d / "vtk") for d in ("thread", "in-line"))
    assert len(in_line) > 100 and sorted(threaded) == sorted(in_line)
    assert [n for n in in_line if threaded[n] != in_line[n]] == []


class Slow:
    """A recorder that takes 20 ms a frame, keeps the frames' times, and fails at ``fail``."""

    def __init__(self, fail: int | None = None) -> None:
        self.times: list[float] = []
        self.closed: list[bool] = []
        self.fail = fail

    def record(self, frame, events: Events) -> None:
        time.sleep(0.02)
        if len(self.times) == self.fail:
            raise OSError(28, "No space left on device")
        self.times.append(frame)

    def close(self, complete: bool = True) -> None:
        self.closed.append(complete)


def test_frames_are_written_in_order_and_close_waits_for_them():
    slow = Slow()
    background = BackgroundRecorder(slow)
    for k in range(6):
        background.record(k, Events())  # type: ignore[arg-type]
    background.close(complete=True)
    assert slow.times == list(range(6)) and slow.closed == [True]


@pytest.mark.parametrize("at_close", [False, True])
def test_a_failure_on_the_thread_is_raised_in_the_run(at_close: bool):
    """The writer fails at its third frame: the error comes out of the next ``record`` (or of
    ``close``), the frames before it are written, and the recorder is closed all the same."""
    slow = Slow(fail=2)
    background = BackgroundRecorder(slow)
    with pytest.raises(OSError, match="No space left"):
        for k in range(3 if at_close else 10):
            background.record(k, Events())  # type: ignore[arg-type]
        background.close(complete=False)
    if not at_close:
        background.close(complete=False)
    assert slow.times == [0, 1] and slow.closed == [False]


def test_a_checkpoint_holds_every_frame_handed_over_and_starts_no_thread():
    slow = Slow()
    background = BackgroundRecorder(slow)
    for k in range(3):
        background.record(k, Events())  # type: ignore[arg-type]
    data = pickle.dumps(background)
    threads = threading.active_count()
    copy = pickle.loads(data)
    assert copy.recorder.times == [0, 1, 2]
    assert threading.active_count() == threads
    copy.record(3, Events())  # type: ignore[arg-type]
    copy.close()
    background.close()
    assert copy.recorder.times == [0, 1, 2, 3] and slow.times == [0, 1, 2]
