"""perga.output.writer_process: the ParaView writer in a process of its own writes the bytes the
in-line writer writes, in order, with the events as they stood at each frame; raises its
failures in the run; is whole at a checkpoint; says so when it dies; outlives Ctrl-C."""

from __future__ import annotations

import os
import pickle
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import perga.run.loop as loop
from perga.model.records import Events
from perga.output.vtk import VtkRecorder
from perga.output.writer_process import (
    WriterDiedError,
    WriterProcess,
    beside,
    packed,
    unpacked,
)
from perga.run import simulate

CASES = Path(__file__).parents[2] / "cases"


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def test_the_process_writes_the_bytes_of_the_writer_in_line(tmp_path, monkeypatch):
    """0.05 s of the bee-bread separator (15 impacts, granules fed and released): every
    ParaView file equal byte for byte to a run whose writer is called in line (the frames'
    impact counts are those at the frame, though the process writes it later)."""
    overrides = ["solver.duration=0.05"]
    case = CASES / "bee-bread-separator.toml"
    record = VtkRecorder.record

    def late(self, frame, events):  # the process behind: the run goes on meanwhile
        time.sleep(0.06)
        record(self, frame, events)

    with monkeypatch.context() as patch:
        patch.setattr(VtkRecorder, "record", late)
        simulate(case, tmp_path / "process", overrides=overrides)
    monkeypatch.setattr(loop, "beside", lambda recorder, directory: recorder)
    simulate(case, tmp_path / "in-line", overrides=overrides)
    forked, in_line = (_files(tmp_path / d / "vtk") for d in ("process", "in-line"))
    assert len(in_line) > 100 and sorted(forked) == sorted(in_line)
    assert [n for n in in_line if forked[n] != in_line[n]] == []


class Log:
    """A recorder that takes 20 ms a frame and appends to ``path`` a line per frame (the frame
    and the impacts it was given) and per close; fails once, at its call ``fail``. Its ``lines`` are
    what the writer process wrote, read back in the run's process."""

    def __init__(self, path: Path, fail: int | None = None) -> None:
        self.path, self.fail, self.calls = path, fail, 0

    def record(self, frame, events: Events) -> None:
        time.sleep(0.02)
        self.calls += 1
        if self.calls - 1 == self.fail:
            raise OSError(28, "No space left on device")
        with self.path.open("a") as f:
            f.write(f"frame {frame} {list(events.impacts)}\n")

    def close(self, complete: bool = True) -> None:
        with self.path.open("a") as f:
            f.write(f"closed {complete}\n")

    def lines(self) -> list[str]:
        return self.path.read_text().splitlines() if self.path.exists() else []


def test_frames_are_written_in_order_with_the_events_at_each(tmp_path):
    """Six frames sent faster than written, the impacts growing by one a frame: the process
    writes them in order, each with the impacts as they stood at it, and ``close`` waits."""
    log = Log(tmp_path / "log")
    writer = beside(log, tmp_path)
    impacts: list[int] = []
    for k in range(6):
        writer.record(k, Events(impacts=impacts))  # type: ignore[arg-type]
        impacts.append(10 + k)
    writer.close(complete=True)
    expected = [f"frame {k} {[10 + i for i in range(k)]}" for k in range(6)]
    assert log.lines() == [*expected, "closed True"]


@pytest.mark.parametrize("at_close", [False, True])
def test_a_failure_in_the_process_is_raised_in_the_run(tmp_path, at_close: bool):
    """The writer fails at its third frame: the error comes out of a later ``record`` (or of
    ``close``), the frames before it are written, and the recorder is closed all the same."""
    log = Log(tmp_path / "log", fail=2)
    writer = beside(log, tmp_path)
    with pytest.raises(OSError, match="No space left"):
        for k in range(3 if at_close else 30):
            writer.record(k, Events())  # type: ignore[arg-type]
        writer.close(complete=False)
    if not at_close:
        writer.close(complete=False)
    assert log.lines() == ["frame 0 []", "frame 1 []", "closed False"]


def test_a_checkpoint_holds_every_frame_sent_and_starts_no_process(tmp_path, monkeypatch):
    """Pickled after three frames, the writer's recorder has written all three; the copy
    forks nothing until its first frame, and goes on from the recorder's state."""
    log = Log(tmp_path / "log")
    writer = beside(log, tmp_path)
    for k in range(3):
        writer.record(k, Events())  # type: ignore[arg-type]
    data = pickle.dumps(writer)
    assert log.lines() == ["frame 0 []", "frame 1 []", "frame 2 []"]
    forks: list[int] = []
    fork = os.fork
    monkeypatch.setattr(os, "fork", lambda: forks.append(1) or fork())
    copy = pickle.loads(data)
    assert forks == [] and copy.recorder.calls == 3
    copy.record(3, Events())  # type: ignore[arg-type]
    assert forks == [1]
    copy.close()
    writer.close()
    assert log.lines()[3:] == ["frame 3 []", "closed True", "closed True"]


def test_a_writer_that_dies_is_named_in_the_run(tmp_path):
    """The process killed (the OOM killer, say): the next frame or the close raises
    WriterDiedError with the process and how it ended, not a broken pipe."""
    writer = beside(Log(tmp_path / "log"), tmp_path)
    assert isinstance(writer, WriterProcess)
    writer.record(0, Events())  # type: ignore[arg-type]
    os.kill(writer._pid, signal.SIGKILL)
    with pytest.raises(WriterDiedError, match=r"writer process \d+ ended \(exit status -9\)"):
        for k in range(1, 100):
            writer.record(k, Events())  # type: ignore[arg-type]
            time.sleep(0.01)
    writer.close()  # closed already: nothing more to say


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_the_process_outlives_a_stop_signal_to_the_process_group(tmp_path, signum):
    """Ctrl-C (or scancel's SIGTERM) reaches every process of the group: the writer ignores it
    and writes on until the run, which stops on it, closes it."""
    log = Log(tmp_path / "log")
    writer = beside(log, tmp_path)
    assert isinstance(writer, WriterProcess)
    writer.record(0, Events())  # type: ignore[arg-type]
    os.kill(writer._pid, signum)
    writer.record(1, Events())  # type: ignore[arg-type]
    writer.close(complete=False)
    assert log.lines() == ["frame 0 []", "frame 1 []", "closed False"]


def test_a_writer_started_from_a_worker_thread_ignores_stop_signals_too(tmp_path):
    """A study's run starts its writer from a Dask worker's thread, not the main one: the
    forked process (whose one thread is then its main thread) still ignores SIGTERM."""
    log = Log(tmp_path / "log")
    started: list[WriterProcess] = []
    thread = threading.Thread(target=lambda: started.append(beside(log, tmp_path)))  # type: ignore[arg-type]
    thread.start()
    thread.join()
    (writer,) = started
    writer.record(0, Events())  # type: ignore[arg-type]
    os.kill(writer._pid, signal.SIGTERM)
    writer.record(1, Events())  # type: ignore[arg-type]
    writer.close()
    assert log.lines() == ["frame 0 []", "frame 1 []", "closed True"]


def test_a_checkpoint_after_a_failed_frame_raises_it(tmp_path):
    """A frame failed and no later frame has been sent: the checkpoint raises the failure
    rather than keep a recorder that missed a frame."""
    log = Log(tmp_path / "log", fail=1)
    writer = beside(log, tmp_path)
    writer.record(0, Events())  # type: ignore[arg-type]
    writer.record(1, Events())  # type: ignore[arg-type]
    with pytest.raises(OSError, match="No space left"):
        pickle.dumps(writer)
    writer.close(complete=False)
    assert log.lines() == ["frame 0 []", "closed False"]


def test_a_message_packed_with_its_arrays_apart_comes_back_equal():
    """Arrays of every kind a frame holds (and a strided view, a 0-d and an empty one) among
    other values, nested: equal values, types and shapes, read-only, in their places."""
    base = np.arange(12.0).reshape(3, 4)
    arrays = [base, base[:, ::2], np.array([True, False]), np.arange(3, dtype=np.int32),
              np.full((), 2.5), np.zeros((0, 2)), np.array([7], dtype=np.int64)]  # fmt: skip
    message = ("frame", {"a": arrays[:3], "b": (1.5, "x", None)}, arrays[3:])
    back = unpacked(packed(message))
    assert back[0] == "frame" and back[1]["b"] == (1.5, "x", None)
    for sent, got in zip(arrays, back[1]["a"] + back[2], strict=True):
        assert got.dtype == sent.dtype and got.shape == sent.shape
        np.testing.assert_array_equal(got, sent)
        assert not got.flags.writeable
