"""Pickles whose paths inside a directory are kept relative to it, so that what a run pickles
(its recorders, with the files they write) goes on in the run directory it is read from, even
after the directory was copied or moved (:mod:`perga.run.checkpoints`,
:mod:`perga.output.writer_process`)."""

from __future__ import annotations

import io
import pickle
from pathlib import Path


class _Pickler(pickle.Pickler):
    """Pickles the paths inside ``root`` as their place in it."""

    def __init__(self, stream: io.BytesIO, root: Path) -> None:
        super().__init__(stream, protocol=pickle.HIGHEST_PROTOCOL)
        self.root = root

    def persistent_id(self, obj: object) -> str | None:
        if isinstance(obj, Path) and obj.is_relative_to(self.root):
            return obj.relative_to(self.root).as_posix()
        return None


class _Unpickler(pickle.Unpickler):
    """Unpickles what :class:`_Pickler` pickled, its paths inside ``root``."""

    def __init__(self, stream: io.BytesIO, root: Path) -> None:
        super().__init__(stream)
        self.root = root

    def persistent_load(self, pid: object) -> Path:
        return self.root / str(pid)


def dumps(obj: object, root: Path) -> bytes:
    """``obj`` pickled, its paths inside the directory ``root`` relative to it."""
    stream = io.BytesIO()
    _Pickler(stream, root).dump(obj)
    return stream.getvalue()


def loads(data: bytes, root: Path) -> object:
    """What :func:`dumps` pickled, its relative paths now inside the directory ``root``."""
    return _Unpickler(io.BytesIO(data), root).load()
