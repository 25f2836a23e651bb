"""``perga run``: a case file through the simulation into a run directory.

Path of a case: ``load_case`` (its schema and names) -> ``compile_case`` (the system, checked)
-> ``Simulation`` stepped at its machine step. Each writer has its own phase-locked clock (its
trigger: tables at ``output.every``, ParaView at ``output.vtk_every``); the simulation advances
to the next step at which a writer, a progress report or a checkpoint is due, and its frame
then goes to the writers due (every writer gets the first frame and the last). The run
directory holds the case file as run, ``scene.json`` (the system's geometry), one table per
recorder (flushed as written), and ``summary.json``, which is written whatever happens:
completed (or completed with its energy ledger off), interrupted (a stop signal) or failed
(NaN, a granule that left the chamber, an error), with the reason.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

from perga.case.schema import Case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case, load_system
from perga.model.system import System
from perga.output.recorders import PhaseLock, Recorder, make_recorders
from perga.output.scene_file import write_scene
from perga.output.tables import drop_converted
from perga.output.vtk import VtkRecorder
from perga.output.writer_process import beside
from perga.run import checkpoints
from perga.run.directory import case_digest, prepare_directory, shown, write_case_copy
from perga.run.guards import RunStoppedError, check_granules, check_population
from perga.run.restart import check_resumable
from perga.run.summary import (
    COMPLETED,
    FINISHED,
    RunSummary,
    describe_end,
    judge_ledger,
    smaller_steps,
    write_summary,
)
from perga.stopping import StopRequest, describe

Progress = Callable[[float, float, int], None]
"""progress(simulated time s, duration s, steps) — called now and then by :func:`run_case`."""


@dataclass
class Writer:
    """A recorder and its trigger: the clock at whose times it takes a frame (``contacts``:
    whether it needs the granules' contact counts)."""

    recorder: Recorder
    trigger: PhaseLock
    contacts: bool


def writers(case: Case, directory: Path, system: System) -> list[Writer]:
    """The recorders ``output.record`` lists, each with its trigger: ParaView's every
    ``output.vtk_every`` (default ``output.every``) in a process of its own, started now
    (:func:`~perga.output.writer_process.beside`), the tables every ``output.every``."""
    out = case.output
    recorders = make_recorders(out.record, directory, system, out.granule_table, out.tables)
    vtk_every = out.vtk_every if out.vtk_every is not None else out.every
    return [
        Writer(
            beside(recorder, directory) if vtk else recorder,
            PhaseLock(vtk_every if vtk else out.every),
            vtk,
        )
        for recorder in recorders
        for vtk in (isinstance(recorder, VtkRecorder),)
    ]


def simulate(
    case: str | Path,
    directory: str | Path,
    *,
    overrides: tuple[str, ...] | list[str] = (),
    overwrite: bool = False,
) -> RunSummary:
    """Run the case file ``case`` with ``overrides`` (``KEY=VALUE``, as ``--set`` takes them)
    into ``directory``, as ``perga run CASE -o DIRECTORY`` does; returns the summary (also in
    summary.json). CaseError for a bad case; FileExistsError for a directory that holds a
    run, unless ``overwrite``."""
    path, directory = Path(case), Path(directory)
    loaded, system = load_system(path, overrides=overrides)
    prepare_directory(directory, overwrite)
    return run_case(loaded, path, directory, system=system)


def run_case(
    case: Case,
    case_path: Path,
    directory: Path,
    progress: Progress | None = None,
    started_from: str = "",
    system: System | None = None,
) -> RunSummary:
    """Simulate ``case`` (its ``system``, compiled by the caller, or here: CaseError) into
    ``directory`` (prepared by the caller); returns the summary, which is also written to
    summary.json. A stop signal (:mod:`perga.stopping`; deferred to the end of
    the build or the next step boundary) and RunStoppedError are recorded in the summary and
    re-raised after everything written so far is flushed; a stop signal also leaves a
    checkpoint to resume from (:func:`resume_run`). ``started_from``: where the granules
    came from, for the summary (``perga run --from``)."""
    summary = RunSummary(
        case=str(case_path.resolve()),
        overrides=[shown(o) for o in case.overrides],
        started_from=started_from,
    )
    start = time.perf_counter()
    run: _Run | None = None
    with StopRequest() as stop:
        try:
            with _ending(summary):
                run = _build(case, system or compile_case(case), case_path, directory, summary,
                             stop)  # fmt: skip
                run.write_frame(summary, run.writers)
                if run.grid is not None:  # from now on a stopped run can be resumed
                    run.checkpoint(summary, start, write=True)
                run.advance(summary, stop, progress, start)
        finally:
            _finish(summary, run, time.perf_counter() - start, directory)
    return summary


def _build(
    case: Case,
    system: System,
    case_path: Path,
    directory: Path,
    summary: RunSummary,
    stop: StopRequest,
) -> _Run:
    """The case's copy, its simulation, scene.json and writers: a run ready for frame 0."""
    write_case_copy(case, case_path, directory / "case.toml")
    record = case.output.record
    options = {"record_impacts": "impacts" in record, "track_energy": "energy" in record}
    run_writers = writers(case, directory, system)  # before the simulation's arrays exist
    try:
        sim = Simulation(system, **options)
        summary.dt, summary.granules, summary.hammers = (
            system.granule_dt,
            len(system.granules),
            len(system.hammers),
        )
        assert system.plan is not None
        summary.time_step = asdict(system.plan) | {"contact_model": system.contact_model.kind}
        summary.contacts = [asdict(p) for p in system.pairs]
        stop.check()
        write_scene(directory, system)
        n_steps = math.ceil(case.solver.duration / sim.dt - 1e-9)
    except BaseException:
        for writer in run_writers:
            writer.recorder.close(complete=False)
        raise
    return _Run(case, directory, sim, run_writers, n_steps)


def resume_run(case: Case, directory: Path, progress: Progress | None = None) -> RunSummary:
    """Go on with the run in ``directory`` from its newest checkpoint (CheckpointError when it
    has none this perga can use): the tables and series are cut back to where they stood then
    and appended to, so that they end as those of a run that never stopped. ``case`` is the
    run's own copy (``case.toml``, loaded), which must be the one the checkpoint was written
    from."""
    check_resumable(directory)
    with StopRequest() as stop:
        sim, handed_over, _ = checkpoints.load(directory, case_digest(directory))
        summary = handed_over["summary"]
        assert isinstance(summary, RunSummary)
        summary.status, summary.reason = "running", ""
        summary.resumed.append(sim.time)
        start = time.perf_counter() - summary.wall_time
        run = _Run(case, directory, sim, handed_over["writers"], handed_over["n_steps"])
        try:
            run.advance(summary, stop, progress, start)
        finally:
            _finish(summary, run, time.perf_counter() - start, directory)
    return summary


@contextmanager
def _ending(summary: RunSummary) -> Iterator[None]:
    """Record in the summary how the block ended if by an exception: interrupted (a stop
    signal), failed (RunStoppedError or another error, with the reason); re-raise."""
    try:
        yield
    except KeyboardInterrupt as exc:
        summary.status, summary.reason = "interrupted", describe(exc)
        raise
    except RunStoppedError as exc:
        summary.status, summary.reason = "failed", str(exc)
        raise
    except Exception as exc:
        summary.status, summary.reason = "failed", f"{type(exc).__name__}: {exc}"
        raise


class _Run:
    """A run under way: the simulation, its writers with their triggers, the steps it is to
    take, and its checkpoint grid (:mod:`perga.run.checkpoints`)."""

    def __init__(
        self, case: Case, directory: Path, sim: Simulation, writers: list[Writer], n_steps: int
    ) -> None:
        self.directory, self.sim, self.writers, self.n_steps = directory, sim, writers, n_steps
        chamber = sim.spec.chamber
        assert chamber is not None
        self.outer, self.thickness = chamber.outer_radius, chamber.wall_thickness
        self.duration = case.solver.duration
        every = case.output.checkpoint_every
        self.grid = PhaseLock(every) if every > 0 else None
        if self.grid is not None:
            self.grid.due(sim.time)  # the grid points after now
        self.every_wall = case.output.checkpoint_wall
        self.last_written = -math.inf
        """When the last checkpoint file was written (time.perf_counter), s."""
        self.case_digest = case_digest(directory)
        self.tables = case.output.tables
        self.ledger_tolerance = case.solver.ledger_tolerance
        self.remedy = smaller_steps(sim.spec)

    def write_frame(self, summary: RunSummary, due: list[Writer]) -> None:
        """The simulation's frame, checked, to the writers ``due``."""
        sim = self.sim
        frame = sim.frame(contacts=any(w.contacts for w in due))
        check_granules(frame, self.outer, self.thickness, sim.dt)
        check_population(frame)
        for writer in due:
            writer.trigger.due(frame.time)
            writer.recorder.record(frame, sim.events())
        summary.frames += 1

    def checkpoint(self, summary: RunSummary, start: float, write: bool) -> None:
        """Take a checkpoint of the run as it stands (between steps), write it if ``write``,
        and go on from it, as a resumed run would."""
        summary.wall_time = time.perf_counter() - start
        summary.checkpoints += write
        handed_over = {"summary": summary, "writers": self.writers, "n_steps": self.n_steps}
        data = checkpoints.dump(self.sim, handed_over, self.directory, self.case_digest)
        if write:
            checkpoints.write(self.directory, self.sim.steps, data)
            self.last_written = time.perf_counter()
        self.sim, _ = checkpoints.read(data)

    def advance(
        self, summary: RunSummary, stop: StopRequest, progress: Progress | None, start: float
    ) -> None:
        """Step to the end, frames as their writers fall due, checkpoints on their grid; the
        summary's status says how it ended."""
        report_every = max(1, self.n_steps // 200)
        with _ending(summary), self.sim.running():
            while self.sim.steps < self.n_steps:
                sim = self.sim
                target = sim.steps + self._steps_to_look(report_every if progress else 0)
                sim.advance_to(target, stop.check)
                stop.check()
                last = sim.steps == self.n_steps
                due = [w for w in self.writers if last or w.trigger.is_due(sim.time)]
                if due:
                    self.write_frame(summary, due)
                if progress and (sim.steps % report_every == 0 or last):
                    progress(sim.time, self.duration, sim.steps)
                if not last and self.grid is not None and self.grid.due(sim.time):
                    write = time.perf_counter() - self.last_written >= self.every_wall
                    self.checkpoint(summary, start, write)
            summary.status = COMPLETED

    def _steps_to_look(self, report_every: int) -> int:
        """The steps the simulation may take at once: to the end, or to the next step at which
        a writer, a progress report (every ``report_every`` steps; 0: none) or a checkpoint is
        due, whichever comes first."""
        sim = self.sim
        steps = [self.n_steps - sim.steps]
        steps += [w.trigger.steps_to_next(sim.steps, sim.dt) for w in self.writers]
        if report_every:
            steps.append(report_every - sim.steps % report_every)
        if self.grid is not None:
            steps.append(self.grid.steps_to_next(sim.steps, sim.dt))
        return min(steps)


def _finish(summary: RunSummary, run: _Run | None, wall: float, directory: Path) -> None:
    """Judge the ledger of a completed run, close the recorders (writing the tables' Parquet
    forms if the run is complete and asks for them) and write summary.json, from the system
    and the simulation's frame at the end; then remove the CSV tables written as Parquet (a
    run stopped before the end keeps its CSV tables, which --resume needs)."""
    frame = None if run is None else run.sim.frame(contacts=False)
    if run is not None and frame is not None and frame.energy is not None:
        summary.energy = asdict(frame.energy)
        if summary.status == COMPLETED:
            judge_ledger(summary, run.ledger_tolerance, run.remedy)
    for writer in [] if run is None else run.writers:
        try:
            writer.recorder.close(complete=summary.status in FINISHED)
        except Exception as exc:  # summary.json must still be written
            summary.warnings.append(f"{type(writer.recorder).__name__}.close failed: {exc}")
    summary.wall_time = wall
    if run is not None and frame is not None:
        describe_end(summary, frame, run.sim.spec, run.sim.threads)
    write_summary(summary, directory)
    if run is not None and run.tables == "parquet" and summary.status in FINISHED:
        drop_converted(directory)
