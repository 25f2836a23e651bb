"""Bytes written whole or not at all, for output that must stay readable when a disk fills up
or a write fails: a table's block (:class:`perga.output.tables.Table` cuts the file back) or a
new file (:func:`write_new` removes it)."""

from __future__ import annotations

import os
from pathlib import Path


def write_all(fd: int, data: bytes) -> None:
    """Write all of ``data`` to the file descriptor ``fd`` (``os.write`` may write part of it;
    this loops until it is all written or a write raises OSError)."""
    view, done = memoryview(data), 0
    while done < len(data):
        done += os.write(fd, view[done:])


def write_new(path: Path, data: bytes) -> None:
    """Create (or replace) ``path`` holding ``data``; if a write fails the file is removed and
    the OSError raised."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
    try:
        write_all(fd, data)
    except OSError:
        os.close(fd)
        path.unlink(missing_ok=True)
        raise
    os.close(fd)


def reopen_at(path: Path, size: int) -> int:
    """A descriptor of the existing file ``path`` for writing at byte ``size``, the file cut to
    that size: going on from a checkpoint. OSError if the file is missing or shorter."""
    fd = os.open(path, os.O_RDWR)
    try:
        if os.fstat(fd).st_size < size:
            raise OSError(
                f"{path} holds {os.fstat(fd).st_size} bytes, fewer than the {size} it held at "
                "the checkpoint"
            )
        os.ftruncate(fd, size)
        os.lseek(fd, size, os.SEEK_SET)
    except OSError:
        os.close(fd)
        raise
    return fd
