"""A recorder run in a process of its own, so that the simulation steps on while a frame is
written: the ParaView writer (:class:`~perga.output.vtk.VtkRecorder`), whose Python (each
file's arrays and headers) then holds no GIL the run's Python waits for
(docs/dev/performance.md).

The process is forked from the run's (``os.fork``: it starts in milliseconds with the
recorder as it is, and may be started from a daemonic process such as a Dask worker). It is
fed through a pipe (:func:`multiprocessing.Pipe`) each frame (the simulation's own copy) and
the events recorded since the last frame, so its recorder sees the events as they stood at the
frame and the files are the bytes a recorder called in line writes. A message goes as its
pickle with the arrays left out and their bytes after it (:func:`packed`): NumPy's own
pickling of a frame's thirty small arrays costs more than their bytes. Sending waits while the
pipe is full, so the process is at most a few frames behind. A failure in it (a full disk)
is raised in the run at the next frame or at :meth:`WriterProcess.close`, every frame before
it whole; the recorder is closed all the same. The process ignores SIGINT and SIGTERM (a
Ctrl-C or ``scancel`` reaches the whole process group): the run, which handles them, closes it.
If the run's process dies, the process writes the frames it was sent and exits, leaving the
files as a stopped run leaves them. Pickling (a checkpoint) takes the recorder's state from the
process once the frames sent are written. Where ``os.fork`` is missing the recorder is called
in line (:func:`beside`).
"""

from __future__ import annotations

import io
import os
import pickle
import select
import signal
from dataclasses import fields
from multiprocessing import Pipe
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import numpy as np

from perga.model.frame import Frame
from perga.model.records import Events
from perga.output import relative_pickle
from perga.output.recorders import Recorder

EVENT_LISTS = tuple(f.name for f in fields(Events))
"""The growing lists of :class:`~perga.model.records.Events`, sent by what is new in them."""


class WriterDiedError(RuntimeError):
    """The writer process ended without being closed."""


def beside(recorder: Recorder, directory: Path) -> Recorder:
    """``recorder`` (writing into the run directory ``directory``) in a process of its own,
    started now (before the simulation's arrays are allocated, which the process would
    otherwise share and copy as the run writes them), or ``recorder`` itself where ``os.fork``
    is missing."""
    if not hasattr(os, "fork"):
        return recorder
    writer = WriterProcess(recorder, directory)
    writer.start()
    return writer


def _portable(exc: BaseException) -> BaseException:
    """``exc``, or a RuntimeError naming it where it cannot be pickled to the run."""
    try:
        pickle.dumps(exc)
    except Exception:
        return RuntimeError(f"{type(exc).__name__}: {exc}")
    return exc


class _ArraysApart(pickle.Pickler):
    """A pickler that leaves each NumPy array out, naming its type and shape in its place,
    and gathers its bytes in ``arrays``."""

    def __init__(self, file: io.BytesIO, arrays: list[memoryview]) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.arrays = arrays

    def persistent_id(self, obj: object) -> tuple[str, tuple[int, ...]] | None:
        if type(obj) is not np.ndarray:
            return None
        self.arrays.append(np.ascontiguousarray(obj).data)
        return obj.dtype.str, obj.shape


class _ArraysAfter(pickle.Unpickler):
    """The unpickler of :class:`_ArraysApart`'s pickle: each array read-only over the
    bytes ``after`` the pickle, in turn."""

    def __init__(self, file: io.BytesIO, after: memoryview) -> None:
        super().__init__(file)
        self.after, self.at = after, 0

    def persistent_load(self, pid: tuple[str, tuple[int, ...]]) -> np.ndarray:
        dtype, shape = np.dtype(pid[0]), pid[1]
        count = int(np.prod(shape))
        array = np.frombuffer(self.after, dtype, count, self.at).reshape(shape)
        self.at += count * dtype.itemsize
        return array


def packed(message: object) -> bytes:
    """``message`` as the length of its pickle without its arrays (8 bytes), that pickle and
    the arrays' bytes (:func:`unpacked` reads it)."""
    arrays: list[memoryview] = []
    head = io.BytesIO()
    _ArraysApart(head, arrays).dump(message)
    return b"".join([len(head.getbuffer()).to_bytes(8, "little"), head.getvalue(), *arrays])


def unpacked(data: bytes) -> Any:
    """The message :func:`packed` gave ``data`` for; its arrays read-only over ``data``."""
    size = int.from_bytes(data[:8], "little")
    view = memoryview(data)
    return _ArraysAfter(io.BytesIO(view[8 : 8 + size]), view[8 + size :]).load()


def _serve(recorder: Recorder, directory: Path, conn: Connection) -> None:
    """The process's loop: frames to ``recorder`` until told to close, or until the run's end
    of the pipe is gone (the run died: the files stay as they stand)."""
    events: dict[str, list[Any]] = {name: [] for name in EVENT_LISTS}
    failed = False
    while True:
        try:
            message = unpacked(conn.recv_bytes())
        except (EOFError, OSError):
            return
        kind = message[0]
        if kind == "frame":
            for name, new in message[2].items():
                events[name].extend(new)
            if not failed:
                try:
                    recorder.record(message[1], Events(**events))
                except Exception as exc:
                    failed = True
                    conn.send(("failed", _portable(exc)))
        elif kind == "state":
            conn.send(("state", relative_pickle.dumps(recorder, directory)))
        else:  # close
            try:
                recorder.close(message[1])
            except Exception as exc:
                conn.send(("closed", _portable(exc)))
            else:
                conn.send(("closed", None))
            return


class WriterProcess:
    """``recorder`` (any :class:`~perga.output.recorders.Recorder`, writing into the run
    directory ``directory``) fed frames in a process of its own (module doc). Until
    :meth:`start` (or the first frame) it is the recorder itself, which :attr:`recorder` holds;
    after, the process holds it."""

    def __init__(self, recorder: Recorder, directory: Path) -> None:
        self.recorder: Recorder | None = recorder
        self.directory = directory
        self._conn: Connection | None = None
        self._pid = 0
        self._status = ""
        self._sent = dict.fromkeys(EVENT_LISTS, 0)
        self._error: BaseException | None = None
        self._reported = False
        self._closed = False
        self._replies = select.poll()
        """The pipe's end watched for a failure, one system call a frame."""

    def start(self) -> None:
        """Fork the process, which takes the recorder with it."""
        assert self._conn is None and self.recorder is not None
        ours, theirs = Pipe()
        stops = {signal.SIGINT, signal.SIGTERM}
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, stops)  # until the child ignores them
        pid = os.fork()
        if pid == 0:  # the writer process: never returns
            code = 1
            try:
                for signum in stops:
                    signal.signal(signum, signal.SIG_IGN)
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)
                ours.close()
                _serve(self.recorder, self.directory, theirs)
                code = 0
            finally:
                os._exit(code)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        theirs.close()
        self._conn, self._pid, self.recorder = ours, pid, None
        self._replies.register(ours.fileno(), select.POLLIN)

    def _died(self, exc: BaseException) -> WriterDiedError:
        """The error for a process found gone (``exc``: what the pipe said)."""
        self._closed = True
        assert self._conn is not None
        self._conn.close()
        return WriterDiedError(
            f"the ParaView writer process {self._pid} ended ({self._reap()}): {exc}"
        )

    def _reap(self) -> str:
        """Wait for the process to end (once); how it ended."""
        if self._pid:
            _, status = os.waitpid(self._pid, 0)
            self._pid = 0
            self._status = f"exit status {os.waitstatus_to_exitcode(status)}"
        return self._status

    def _send(self, message: tuple[Any, ...]) -> None:
        assert self._conn is not None
        try:
            self._conn.send_bytes(packed(message))
        except OSError as exc:
            raise self._died(exc) from exc

    def _receive(self, kind: str) -> Any:
        """The process's reply ``kind`` (a failure reported before it is kept)."""
        assert self._conn is not None
        while True:
            try:
                message = self._conn.recv()
            except (EOFError, OSError) as exc:
                raise self._died(exc) from exc
            if message[0] == "failed":
                self._error = message[1]
            elif message[0] == kind:
                return message[1]

    def _raise(self) -> None:
        """Raise the process's failure, once (the frames after it are not written)."""
        if self._conn is not None and not self._closed:
            while self._error is None and self._replies.poll(0):
                self._receive("failed")
        if self._error is not None and not self._reported:
            self._reported = True
            raise self._error

    def record(self, frame: Frame, events: Events) -> None:
        """Send ``frame`` and the events since the last frame to the process (waits while
        the pipe is full); raises what made an earlier frame fail."""
        self._raise()
        if self._conn is None:
            self.start()
        new = {}
        for name in EVENT_LISTS:
            items = getattr(events, name)
            new[name], self._sent[name] = list(items[self._sent[name] :]), len(items)
        self._send(("frame", frame, new))

    def close(self, complete: bool = True) -> None:
        """Write the frames sent, close the recorder and end the process (idempotent); raises
        what made a frame or the closing fail."""
        if self._closed:
            return
        self._closed = True
        if self._conn is None:
            assert self.recorder is not None
            self.recorder.close(complete)
            return
        try:
            self._send(("close", complete))
            failed = self._receive("closed")
        finally:
            self._conn.close()
            self._reap()
        self._raise()
        if failed is not None:
            raise failed

    def __getstate__(self) -> dict[str, object]:
        """The recorder, pickled with its paths relative to the run directory (which may be
        moved before the run goes on), once the frames sent are written (a checkpoint); raises
        what made one fail."""
        if self._conn is None:
            state = relative_pickle.dumps(self.recorder, self.directory)
        else:
            self._send(("state",))
            state = self._receive("state")
            self._raise()
        return {"recorder": state, "directory": self.directory}

    def __setstate__(self, state: dict[str, object]) -> None:
        """Go on from a checkpoint: the recorder as it was, a new process at the next frame."""
        data, directory = state["recorder"], state["directory"]
        assert isinstance(data, bytes) and isinstance(directory, Path)
        self.__init__(relative_pickle.loads(data, directory), directory)  # type: ignore[misc]
