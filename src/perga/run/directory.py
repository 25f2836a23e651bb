"""A run directory: locked for the run's life, made empty (or refused), the case copied into
it as run with the geometry files it uses (a directory complete on its own, wherever it is
moved), its digest."""

from __future__ import annotations

import copy
import fcntl
import hashlib
import os
import shutil
from pathlib import Path
from types import TracebackType
from typing import Any, Self

import tomli_w

from perga.case.files import file_tables
from perga.case.schema import Case

LOCK = ".perga.lock"
"""The run directory's lock file: the pid of the run that holds it (:class:`DirectoryLock`)."""
GEOMETRY = "geometry"
"""The run directory's folder of copies of the geometry files its case uses."""
DIGESTS = "SHA256SUMS"
"""The copies' SHA-256 digests in ``geometry/``, in the form ``sha256sum -c`` checks."""


class DirectoryLockedError(Exception):
    """Another perga run holds the run directory's lock: the message names it and its pid."""


class DirectoryLock:
    """An exclusive lock on a run directory: ``fcntl.flock`` on its file :data:`LOCK`, taken
    before anything in the directory is touched and held for the run's life (the OS drops it
    when the process ends, however it ends); the file is removed on :meth:`release`."""

    def __init__(self, directory: Path) -> None:
        """Take the lock of ``directory`` (made if missing): DirectoryLockedError at once if
        another process holds it, OSError if the directory cannot be made."""
        directory.mkdir(parents=True, exist_ok=True)
        self.path = directory / LOCK
        self._fd: int | None = _locked(self.path)
        os.ftruncate(self._fd, 0)
        os.write(self._fd, f"{os.getpid()}\n".encode())

    def release(self) -> None:
        """Remove the lock file and drop the lock (idempotent)."""
        if self._fd is None:
            return
        if _same_file(self._fd, self.path):  # removed while locked: no one waits on it
            self.path.unlink()
        os.close(self._fd)
        self._fd = None

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.release()


def _locked(path: Path) -> int:
    """A descriptor of the lock file ``path`` holding its lock (made if missing); a file its
    holder removed after this process opened it is passed over for the one now at ``path``."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 32).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise DirectoryLockedError(
                f"{path.parent} is being written by another perga run (pid {holder})"
            ) from None
        if _same_file(fd, path):
            return fd
        os.close(fd)


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` is the file open as ``fd``."""
    try:
        return os.path.samestat(os.fstat(fd), path.stat())
    except FileNotFoundError:
        return False


def prepare_directory(directory: Path, overwrite: bool) -> None:
    """Create the run directory; refuse one that holds anything but its lock file unless
    ``overwrite`` (FileExistsError), which empties it (the lock file kept: a lock taken
    before stays held)."""
    held = [p for p in directory.iterdir() if p.name != LOCK] if directory.exists() else []
    if held:
        if not overwrite:
            raise FileExistsError(
                f"{directory} already holds a run: choose another -o DIR or pass --overwrite"
            )
        for path in held:
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
    directory.mkdir(parents=True, exist_ok=True)


def write_case_copy(case: Case, case_path: Path, destination: Path) -> None:
    """The case as run: the file itself, or with overrides or geometry files the file's data
    with the overrides applied and its geometry paths pointing at the copies
    (:func:`copy_geometry`; TOML, what changed listed in a comment at the top)."""
    data = copy_geometry(case, destination.parent)
    if data is None and (not case.overrides or case.source_data is None):
        shutil.copyfile(case_path, destination)
        return
    notes = [f"its geometry files copied into {GEOMETRY}/"] if data is not None else []
    notes += ["with these overrides:"] if case.overrides else []
    header = "".join(f"# --set {shown(o)}\n" for o in case.overrides)
    text = f"# {case_path} as run, {', '.join(notes)}\n{header}\n" + tomli_w.dumps(
        data if data is not None else case.source_data, multiline_strings=True
    )
    destination.write_text(text, encoding="utf-8")


def copy_geometry(case: Case, directory: Path) -> dict[str, Any] | None:
    """Copy the geometry files ``case`` uses into ``directory/geometry/`` (each under its own
    name, numbered where two share one) with their SHA-256 digests (:data:`DIGESTS`); the
    case's data with each file's path pointing at its copy (relative to ``directory``), or
    None for a case that uses none."""
    data = copy.deepcopy(case.source_data)
    shapes = list(file_tables(data))
    if not shapes:
        return None
    folder = directory / GEOMETRY
    folder.mkdir(exist_ok=True)
    names: dict[Path, str] = {}
    digests = []
    for shape in shapes:
        source = ((case.source_dir or Path()) / shape["path"]).resolve()
        if source not in names:
            taken = source.name in names.values()
            names[source] = f"{len(names)}-{source.name}" if taken else source.name
            content = source.read_bytes()
            (folder / names[source]).write_bytes(content)
            digests.append(f"{hashlib.sha256(content).hexdigest()}  {names[source]}\n")
        shape["path"] = f"{GEOMETRY}/{names[source]}"
    (folder / DIGESTS).write_text("".join(digests), encoding="utf-8")
    return data


def changed_geometry(directory: Path) -> list[str]:
    """The run's copies of its geometry files (``geometry/``) that are missing or differ
    from the SHA-256 digests recorded when they were copied, each as a problem naming it."""
    digests = directory / GEOMETRY / DIGESTS
    if not digests.is_file():
        return []
    problems = []
    for line in digests.read_text(encoding="utf-8").splitlines():
        digest, _, name = line.partition("  ")
        path = directory / GEOMETRY / name
        try:
            found = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError as exc:
            problems.append(f"{path}: cannot read ({exc.strerror})")
            continue
        if found != digest:
            problems.append(
                f"{path}: changed since the run copied it (its SHA-256 is not the one in {digests})"
            )
    return problems


def shown(override: str, most: int = 200) -> str:
    """An override as listed in a run's case copy and summary: whole, or cut after ``most``
    characters (an explicit placement of a run's granules, ``perga run --from``, is in the
    case copy itself)."""
    if len(override) <= most:
        return override
    return f"{override[: most // 2]}... ({len(override)} characters)"


def case_digest(directory: Path) -> str:
    """SHA-256 of the run's copy of its case file."""
    return hashlib.sha256((directory / "case.toml").read_bytes()).hexdigest()
