"""What ``perga run`` is asked: a case (with overrides, or started from another run's granules)
into a directory, or a stopped run to go on with; checked, its case loaded and its directory
ready (:func:`prepare`), then run (:func:`execute`), and the outcome in words
(:func:`outcome`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from perga.case import load_case
from perga.case.schema import Case
from perga.model.compile import check_parameters, compile_case
from perga.model.system import System
from perga.run.checkpoints import CheckpointError
from perga.run.directory import (
    DirectoryLock,
    DirectoryLockedError,
    changed_geometry,
    prepare_directory,
)
from perga.run.loop import Progress, resume_run, run_case
from perga.run.restart import RunStateError, case_from_run, check_resumable
from perga.run.summary import LEDGER_OFF, RunSummary, ledger_closure_text


class BadRequestError(Exception):
    """A request that cannot be run; the message says why (exit status 2)."""


@dataclass(frozen=True)
class Request:
    """``perga run``'s arguments: ``case`` (a case file) or ``resume`` (a run directory), the
    ``output`` directory (default ``output.directory``), ``overwrite``, the ``overrides``
    (``KEY=VALUE``) and ``start_from`` (``RUN[:TIME]``, perga run --from)."""

    case: Path | None = None
    resume: Path | None = None
    output: Path | None = None
    overwrite: bool = False
    overrides: tuple[str, ...] = ()
    start_from: str | None = None


@dataclass(frozen=True)
class Prepared:
    """A request ready to run: its case, its system (None to go on with a stopped run, whose
    checkpoint holds the simulation), its directory and the directory's lock, held until
    :func:`execute` ends."""

    request: Request
    case: Case
    system: System | None
    directory: Path
    lock: DirectoryLock

    @property
    def resume(self) -> bool:
        """Whether this goes on with a stopped run."""
        return self.request.resume is not None


def load(request: Request) -> tuple[Case, System | None]:
    """The request's case and its system, compiled and checked (BadRequestError; CaseError for a
    bad case file); a stopped run's case, whose system its checkpoint holds (None)."""
    r = request
    if (r.case is None) == (r.resume is None):
        raise BadRequestError("perga run needs a CASE or --resume RUN (one of them)")
    if r.resume is not None:
        if r.overrides or r.output or r.overwrite or r.start_from:
            raise BadRequestError(
                "--resume RUN goes on with the run as it was: no --set, -o, --overwrite, --from"
            )
        if not (r.resume / "case.toml").is_file():
            raise BadRequestError(f"{r.resume} is not a perga run (it has no case.toml)")
        if changed := changed_geometry(r.resume):
            raise BadRequestError(f"cannot resume: {'; '.join(changed)}")
        return load_case(r.resume / "case.toml"), None
    assert r.case is not None
    if r.start_from is not None:
        try:
            case = case_from_run(r.case, list(r.overrides), r.start_from)
        except RunStateError as exc:
            raise BadRequestError(str(exc)) from None
    else:
        case = load_case(r.case, overrides=r.overrides)
    if case.chamber is None:  # a parameter set (for paper-check), not a scene
        check_parameters(case)
        raise BadRequestError(
            f"{r.case}: [chamber] is missing: perga run needs the wall around the rotor "
            "(a case without one is a parameter set for perga paper-check)"
        )
    return case, compile_case(case)


def prepare(request: Request, case: Case, system: System | None) -> Prepared:
    """The run directory of ``request`` locked (before anything in it is touched) and made
    ready for ``case`` and ``system`` (:func:`load`'s): BadRequestError for a directory
    another run holds, a run with nothing to resume, or a directory that holds a run (without
    ``overwrite``) or cannot be made."""
    directory = request.resume or request.output
    if directory is None:
        assert request.case is not None
        directory = Path(case.output.directory.format(case=request.case.stem))
    lock = _lock(directory)
    try:
        if request.resume is not None:
            check_resumable(directory)
        else:
            prepare_directory(directory, request.overwrite)
    except CheckpointError as exc:
        lock.release()
        raise BadRequestError(f"cannot resume: {exc}") from None
    except FileExistsError as exc:
        lock.release()
        raise BadRequestError(str(exc)) from None
    except OSError as exc:
        lock.release()
        raise _unusable(directory, exc) from None
    return Prepared(request, case, system, directory, lock)


def _lock(directory: Path) -> DirectoryLock:
    """The lock of the run ``directory`` (BadRequestError if another run holds it or the
    directory cannot be made)."""
    try:
        return DirectoryLock(directory)
    except DirectoryLockedError as exc:
        raise BadRequestError(str(exc)) from None
    except OSError as exc:
        raise _unusable(directory, exc) from None


def _unusable(directory: Path, exc: OSError) -> BadRequestError:
    """A run directory that cannot be made or written: a file in the way, no permission, a
    read-only file system."""
    return BadRequestError(
        f"cannot make the run directory {directory}: {exc.strerror or exc}; choose another -o DIR"
    )


def execute(prepared: Prepared, progress: Progress | None = None) -> RunSummary:
    """Run (or go on with) the prepared run; the summary. BadRequestError where the run's
    checkpoints cannot be used; a stop signal, RunStoppedError or OSError (the run's output
    cannot be written) propagate, everything written so far kept. The directory's lock is
    released at the end."""
    with prepared.lock:
        if prepared.resume:
            try:
                return resume_run(prepared.case, prepared.directory, progress)
            except CheckpointError as exc:
                raise BadRequestError(f"cannot resume: {exc}") from None
        request = prepared.request
        assert request.case is not None
        return run_case(
            prepared.case,
            request.case,
            prepared.directory,
            progress,
            request.start_from or "",
            system=prepared.system,
        )


def outcome(summary: RunSummary, directory: Path) -> tuple[list[str], list[str], int]:
    """What a finished run says: lines for stdout, lines for stderr and the exit status (0, or
    3 for a run whose energy ledger is off)."""
    status = summary.status
    if status == LEDGER_OFF:
        status = f"completed, ledger off by {summary.energy['closure']:+.2%}"
    out = [
        f"{status}: {summary.steps} steps, {summary.simulated_time:.4g} s simulated in "
        f"{summary.wall_time:.3g} s, {summary.impacts} impacts -> {directory}"
    ]
    pop = summary.population
    if pop and (pop["fed"] != summary.granules or pop["released"] or pop["departed"]):
        out.append(
            f"granules: {pop['fed']} fed, {pop['released']} released from cells, "
            f"{pop['departed']} departed, {pop['broken']} broken, {pop['present']} present"
        )
    facts = []
    if summary.energy:
        facts.append(f"energy ledger closes to {ledger_closure_text(summary.energy)}")
    if summary.speeds:
        facts.append(
            f"granule speeds at the end {summary.speeds['mean']:.3g} m/s mean, "
            f"{summary.speeds['max']:.3g} max"
        )
    out.append("; ".join([*facts, f"figures: perga report {directory}"]))
    state = directory / "vtk" / "paraview_state.py"
    if state.exists():
        out.append(f"ParaView: paraview --state={state}")
    err = [f"warning: {w}" for w in summary.warnings]
    if summary.status == LEDGER_OFF:
        err.append(f"error: {summary.reason}")
        return out, err, 3
    return out, err, 0
