"""A recorder run on a thread of its own, so that the simulation steps on while a frame is
written: the ParaView writer (:class:`~perga.output.vtk.VtkRecorder`), whose work is mostly
zlib's compression and file writing, which run without Python's GIL (as do the compiled soft
steps, ``nogil``), so the two overlap on two cores.

The frames handed over are the simulation's own copies (:meth:`~perga.engine.simulation.
Simulation.frame` builds new arrays each time) and the events as they stood at the frame
(:func:`events_at`), so the files are the bytes a recorder called in line writes. The thread
writes frames in the order given, at most :data:`DEPTH` behind the simulation; a failure in it
(a full disk) is raised in the run's thread at the next frame or at :meth:`close`, so the run
ends saying why with every frame before it whole. Pickling (a checkpoint) waits for the frames
handed over to be written first.
"""

from __future__ import annotations

import queue
import threading
from dataclasses import replace

from perga.model.frame import Frame
from perga.model.records import Events
from perga.output.recorders import Recorder

DEPTH = 2
"""Frames the writer thread may be behind the simulation before ``record`` waits."""


def events_at(events: Events) -> Events:
    """``events`` as they stand now: the growing lists cut at their present lengths."""
    return replace(
        events,
        impacts=events.impacts[:],
        releases=events.releases[:],
        departures=events.departures[:],
        contacts=events.contacts[:],
    )


class BackgroundRecorder:
    """``recorder`` (any :class:`~perga.output.recorders.Recorder`) fed frames on a thread of its
    own (module doc)."""

    def __init__(self, recorder: Recorder) -> None:
        self.recorder = recorder
        self._frames: queue.Queue[tuple[Frame, Events] | None] = queue.Queue(maxsize=DEPTH)
        self._error: BaseException | None = None
        self._reported = False
        self._thread: threading.Thread | None = None
        """Started at the first frame (a copy unpickled from a checkpoint and never fed has
        none)."""

    def _write(self) -> None:
        while (item := self._frames.get()) is not None:
            try:
                if self._error is None:
                    self.recorder.record(*item)
            except BaseException as exc:  # raised in the run's thread (_raise)
                self._error = exc
            finally:
                self._frames.task_done()
        self._frames.task_done()

    def _raise(self) -> None:
        """Raise the writer's failure, once (the frames after it are not written)."""
        if self._error is not None and not self._reported:
            self._reported = True
            raise self._error

    def record(self, frame: Frame, events: Events) -> None:
        """Hand ``frame`` and the events so far to the writer thread (waits while it is
        :data:`DEPTH` frames behind); raises what made an earlier frame fail."""
        self._raise()
        if self._thread is None:
            self._thread = threading.Thread(target=self._write, name="perga-writer", daemon=True)
            self._thread.start()
        self._frames.put((frame, events_at(events)))

    def flush(self) -> None:
        """Wait until every frame handed over is written; raises what made one fail."""
        self._frames.join()
        self._raise()

    def close(self, complete: bool = True) -> None:
        """Write the frames handed over, stop the thread and close the recorder (idempotent)."""
        if self._thread is not None and self._thread.is_alive():
            self._frames.join()
            self._frames.put(None)
            self._thread.join()
        try:
            self._raise()
        finally:
            self.recorder.close(complete)

    def __getstate__(self) -> dict[str, object]:
        """The recorder once the frames handed over are written (a checkpoint)."""
        self.flush()
        return {"recorder": self.recorder}

    def __setstate__(self, state: dict[str, object]) -> None:
        """Go on from a checkpoint (a new writer thread at the next frame)."""
        self.__init__(state["recorder"])  # type: ignore[misc, arg-type]
