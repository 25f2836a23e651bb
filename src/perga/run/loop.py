"""``perga run``: a case file through the engine into a run directory.

Path of a case: ``load_case`` (validation) -> ``scene_spec`` (the system) -> ``Simulation``
stepped at its machine step; after every step the phase-locked frame clock decides whether the
simulation's frame goes to the recorders (so the last frame is always written at the end). The
run directory holds the case file as run, ``scene.json`` (the system's geometry), one CSV per
recorder (flushed as written), and ``summary.json``, which is written whatever happens:
completed (or completed with its energy ledger off), interrupted (Ctrl-C) or failed (NaN, a
granule that left the chamber, an error), with the reason.
"""

from __future__ import annotations

import hashlib
import json
import math
import shutil
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import tomli_w

from perga import checkpoints
from perga.case.schema import Case
from perga.case.timestep import contact_plan
from perga.engine.simulation import Simulation
from perga.geometry.clearance import overlapping_pairs
from perga.model.frame import Frame
from perga.model.from_case import scene_spec
from perga.output.recorders import PhaseLock, Recorder, make_recorders
from perga.output.scene_file import write_scene
from perga.output.tables import read_columns, table_path
from perga.stopping import StopRequest, describe

COMPLETED = "completed"
LEDGER_OFF = "completed, ledger off"
"""The status of a run that reached its end with its energy ledger's closure beyond
``solver.ledger_tolerance``: its results are all there, but not to be trusted as they are."""
FINISHED = (COMPLETED, LEDGER_OFF)
"""The statuses of a run that reached its end (nothing to resume)."""


class RunStoppedError(Exception):
    """The simulation cannot go on; the message names the step, the granule and a remedy."""


@dataclass
class RunSummary:
    """What summary.json holds (SI units)."""

    case: str
    overrides: list[str] = field(default_factory=list)
    started_from: str = ""
    """The run and time whose granules this run started from (perga run --from), if any."""
    status: str = "running"
    reason: str = ""
    steps: int = 0
    dt: float = 0.0
    time_step: dict[str, float | str] = field(default_factory=dict)
    contacts: list[dict[str, object]] = field(default_factory=list)
    """Soft contacts: per contact kind its materials, stiffness, damping and the convention
    that gives it from e, duration and steps per contact, k_t/k_n, and the tangential
    half-period of a sticking contact with its steps (:class:`perga.case.timestep.PairPlan`)."""
    simulated_time: float = 0.0
    wall_time: float = 0.0
    steps_per_second: float = 0.0
    granules: int = 0
    hammers: int = 0
    impacts: int = 0
    frames: int = 0
    population: dict[str, int] = field(default_factory=dict)
    """Granules: fed (those at t = 0 included), released from cells, departed through the
    outlet, broken (drawn), removed broken, present at the end."""
    energy: dict[str, float] = field(default_factory=dict)
    threads: int = 1
    """CPU threads the contact model used."""
    speeds: dict[str, float] = field(default_factory=dict)
    """The granules' speeds at the end, m/s: mean and max (none present: empty)."""
    checkpoints: int = 0
    """Checkpoints written (RUN/checkpoints/, the last two kept)."""
    resumed: list[float] = field(default_factory=list)
    """Simulated times, s, at which the run was resumed from a checkpoint."""
    warnings: list[str] = field(default_factory=list)


def write_case_copy(case: Case, case_path: Path, destination: Path) -> None:
    """The case as run: the file itself, or with overrides the file's data with them applied
    (TOML, the overrides listed in a comment at the top)."""
    if not case.overrides or case.source_data is None:
        shutil.copyfile(case_path, destination)
        return
    header = "".join(f"# --set {shown(o)}\n" for o in case.overrides)
    text = f"# {case_path} as run, with these overrides:\n{header}\n" + tomli_w.dumps(
        case.source_data, multiline_strings=True
    )
    destination.write_text(text, encoding="utf-8")


class RunStateError(Exception):
    """A run's state cannot be taken (``perga run --from``): the message says why."""


def granules_of_run(run: Path, time: float | None = None) -> tuple[float, list[str], np.ndarray]:
    """The granules of the run directory ``run`` at its last frame at or before ``time`` (s;
    None: its last frame), as case overrides that start a case from them: (the frame's time,
    ``granules.count`` and an explicit ``granules.placement`` with positions, velocities, spins
    and the frame's largest overlap of two granules allowed, their radii, m). RunStateError if
    the run has no granule table or no such frame."""
    path = table_path(run, "granules")
    if path is None:
        raise RunStateError(f"{run} has no granule table (granules.csv or granules.parquet)")
    try:
        table = read_columns(path)
    except (OSError, ValueError) as exc:
        raise RunStateError(f"{path}: cannot read ({exc})") from None
    times = table["time"]
    chosen = times if time is None else times[times <= time * (1 + 1e-12)]
    if chosen.size == 0:
        raise RunStateError(f"{path}: no frame at or before t = {time} s")
    rows = times == chosen.max()
    x, y, vx, vy, spins = (
        table[c][rows].tolist() for c in ("x", "y", "vx", "vy", "angular_velocity")
    )  # Python floats: their repr is TOML
    overlap = largest_overlap(np.column_stack((x, y)), table["radius"][rows])
    placement = (
        f'{{kind = "explicit", overlap = {overlap!r}, '
        f"positions = [{', '.join(f'[{a!r}, {b!r}]' for a, b in zip(x, y, strict=True))}], "
        f"velocities = [{', '.join(f'[{a!r}, {b!r}]' for a, b in zip(vx, vy, strict=True))}], "
        f"angular_velocities = [{', '.join(repr(w) for w in spins)}]}}"
    )
    overrides = [f"granules.count={int(rows.sum())}", f"granules.placement={placement}"]
    return float(chosen.max()), overrides, table["radius"][rows]


def largest_overlap(positions: np.ndarray, radii: np.ndarray) -> float:
    """The largest overlap of two of the discs, m (0 if none overlap)."""
    pairs = overlapping_pairs(positions, radii)
    if len(pairs) == 0:
        return 0.0
    gap = np.hypot(*(positions[pairs[:, 0]] - positions[pairs[:, 1]]).T)
    return float(np.max(radii[pairs[:, 0]] + radii[pairs[:, 1]] - gap))


def shown(override: str, most: int = 200) -> str:
    """An override as listed in a run's case copy and summary: whole, or cut after ``most``
    characters (an explicit placement of a run's granules, ``perga run --from``, is in the
    case copy itself)."""
    if len(override) <= most:
        return override
    return f"{override[: most // 2]}... ({len(override)} characters)"


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
    from perga.case import load_case

    path, directory = Path(case), Path(directory)
    loaded = load_case(path, overrides=list(overrides))
    prepare_directory(directory, overwrite)
    return run_case(loaded, path, directory)


def prepare_directory(directory: Path, overwrite: bool) -> None:
    """Create the run directory; refuse a non-empty one unless ``overwrite`` (FileExistsError)."""
    if directory.exists() and any(directory.iterdir()):
        if not overwrite:
            raise FileExistsError(
                f"{directory} already holds a run: choose another -o DIR or pass --overwrite"
            )
        shutil.rmtree(directory)
    directory.mkdir(parents=True, exist_ok=True)


def check_granules(frame: Frame, chamber_radius: float, wall_thickness: float, dt: float) -> None:
    """Raise RunStoppedError for a non-finite state or a granule outside the chamber wall
    (farther from the axis than the wall's farthest inner point, ``chamber_radius``, plus its
    thickness); ``dt`` (s) is named in the remedy."""
    p, v = frame.granules.positions, frame.granules.velocities
    ids = frame.granules.ids
    bad = np.nonzero(~np.all(np.isfinite(np.hstack((p, v))), axis=1))[0]
    if bad.size:
        raise RunStoppedError(
            f"step {frame.step} (t = {frame.time:.6g} s): granule {ids[bad[0]]} has a non-finite "
            f"position or velocity; reduce solver.dt (now {dt:.3g} s)"
        )
    r = np.hypot(p[:, 0], p[:, 1])
    out = np.nonzero(r > chamber_radius + wall_thickness)[0]
    if out.size:
        i = out[0]
        raise RunStoppedError(
            f"step {frame.step} (t = {frame.time:.6g} s): granule {ids[i]} left the chamber "
            f"(r = {r[i]:.4g} m > wall at {chamber_radius:g} m + {wall_thickness:g} m): it "
            f"tunnelled through the wall; reduce solver.dt (now {dt:.3g} s) or increase "
            "chamber.wall_thickness"
        )


def check_population(frame: Frame) -> None:
    """Raise RunStoppedError unless every granule fed is present, departed or removed broken."""
    present = len(frame.granules.ids)
    if frame.fed != present + frame.departed + frame.removed_broken:
        raise RunStoppedError(
            f"step {frame.step} (t = {frame.time:.6g} s): granules not conserved: {frame.fed} "
            f"fed != {present} present + {frame.departed} departed + {frame.removed_broken} "
            "removed broken (a defect of perga: please report it with the case file)"
        )


Progress = Callable[[float, float, int], None]
"""progress(simulated time s, duration s, steps) — called now and then by :func:`run_case`."""


def run_case(
    case: Case,
    case_path: Path,
    directory: Path,
    progress: Progress | None = None,
    started_from: str = "",
) -> RunSummary:
    """Simulate ``case`` into ``directory`` (prepared by the caller); returns the summary, which
    is also written to summary.json. A stop signal (:mod:`perga.stopping`; deferred to the end of
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
                run = _build(case, case_path, directory, summary, stop)
                run.frames.due(0.0)
                run.write_frame(summary)
                if run.grid is not None:  # from now on a stopped run can be resumed
                    run.checkpoint(summary, start, write=True)
                run.advance(summary, stop, progress, start)
        finally:
            _finish(summary, run, time.perf_counter() - start, directory)
    return summary


def _build(
    case: Case, case_path: Path, directory: Path, summary: RunSummary, stop: StopRequest
) -> _Run:
    """The case's copy, its simulation, scene.json and recorders: a run ready for frame 0."""
    write_case_copy(case, case_path, directory / "case.toml")
    spec = scene_spec(case)
    record = case.output.record
    options = {"record_impacts": "impacts" in record, "track_energy": "energy" in record}
    sim = Simulation(spec, **options)
    summary.dt, summary.granules, summary.hammers = (
        spec.granule_dt,
        len(spec.granules),
        len(spec.hammers),
    )
    assert spec.plan is not None
    summary.time_step = asdict(spec.plan) | {"contact_model": spec.contact_model.kind}
    if case.contact_model.soft:
        summary.contacts = [asdict(p) for p in contact_plan(case, spec.granule_dt)]
    stop.check()
    write_scene(directory, spec)
    recorders = make_recorders(record, directory, spec, case.output.granule_table)
    n_steps = math.ceil(case.solver.duration / sim.dt - 1e-9)
    return _Run(case, directory, sim, recorders, PhaseLock(case.output.every), n_steps)


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
        run = _Run(case, directory, sim, handed_over["recorders"], handed_over["frames"],
                   handed_over["n_steps"])  # fmt: skip
        try:
            run.advance(summary, stop, progress, start)
        finally:
            _finish(summary, run, time.perf_counter() - start, directory)
    return summary


def check_resumable(directory: Path) -> None:
    """CheckpointError unless the run in ``directory`` stopped before its end (a run killed
    before it wrote summary.json counts as stopped)."""
    summary = directory / "summary.json"
    try:
        text = summary.read_text(encoding="utf-8") if summary.is_file() else "{}"
        status = json.loads(text).get("status")
    except (OSError, ValueError, AttributeError):
        status = None
    if status in FINISHED:
        raise checkpoints.CheckpointError(f"{directory} {status}: there is nothing to resume")


def case_digest(directory: Path) -> str:
    """SHA-256 of the run's copy of its case file."""
    return hashlib.sha256((directory / "case.toml").read_bytes()).hexdigest()


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
    """A run under way: the simulation, its recorders and frame clock, the steps it is to
    take, and its checkpoint grid (:mod:`perga.checkpoints`)."""

    def __init__(
        self,
        case: Case,
        directory: Path,
        sim: Simulation,
        recorders: list[Recorder],
        frames: PhaseLock,
        n_steps: int,
    ) -> None:
        self.directory, self.sim, self.recorders = directory, sim, recorders
        self.frames, self.n_steps = frames, n_steps
        chamber = sim.spec.chamber
        assert chamber is not None
        self.outer, self.thickness = chamber.outer_radius, chamber.wall_thickness
        self.contacts = "vtk" in case.output.record
        self.duration = case.solver.duration
        every = case.output.checkpoint_every
        self.grid = PhaseLock(every) if every > 0 else None
        if self.grid is not None:
            self.grid.due(sim.time)  # the grid points after now
        self.every_wall = case.output.checkpoint_wall
        self.last_written = -math.inf
        """When the last checkpoint file was written (time.perf_counter), s."""
        self.case_digest = case_digest(directory)
        self.ledger_tolerance = case.solver.ledger_tolerance
        self.remedy = _smaller_steps(case)

    def write_frame(self, summary: RunSummary) -> None:
        """The simulation's frame, checked, to every recorder."""
        sim = self.sim
        frame = sim.frame(contacts=self.contacts)
        check_granules(frame, self.outer, self.thickness, sim.dt)
        check_population(frame)
        for recorder in self.recorders:
            recorder.record(frame, sim.events())
        summary.frames += 1

    def checkpoint(self, summary: RunSummary, start: float, write: bool) -> None:
        """Take a checkpoint of the run as it stands (between steps), write it if ``write``,
        and go on from it, as a resumed run would."""
        summary.wall_time = time.perf_counter() - start
        summary.checkpoints += write
        handed_over = {
            "summary": summary,
            "recorders": self.recorders,
            "frames": self.frames,
            "n_steps": self.n_steps,
        }
        data = checkpoints.dump(self.sim, handed_over, self.directory, self.case_digest)
        if write:
            checkpoints.write(self.directory, self.sim.steps, data)
            self.last_written = time.perf_counter()
        self.sim, _ = checkpoints.read(data)

    def advance(
        self, summary: RunSummary, stop: StopRequest, progress: Progress | None, start: float
    ) -> None:
        """Step to the end, frames as they fall due, checkpoints on their grid; the summary's
        status says how it ended."""
        report_every = max(1, self.n_steps // 200)
        with _ending(summary), self.sim.running():
            while self.sim.steps < self.n_steps:
                sim = self.sim
                sim.advance_to(sim.steps + self._steps_to_look(report_every if progress else 0),
                               stop.check)  # fmt: skip
                stop.check()
                last = sim.steps == self.n_steps
                if self.frames.due(sim.time) or last:
                    self.write_frame(summary)
                if progress and (sim.steps % report_every == 0 or last):
                    progress(sim.time, self.duration, sim.steps)
                if not last and self.grid is not None and self.grid.due(sim.time):
                    write = time.perf_counter() - self.last_written >= self.every_wall
                    self.checkpoint(summary, start, write)
            summary.status = COMPLETED

    def _steps_to_look(self, report_every: int) -> int:
        """The steps the simulation may take at once: to the end, or to the next step at which
        a frame, a progress report (every ``report_every`` steps; 0: none) or a checkpoint is
        due, whichever comes first."""
        sim = self.sim
        steps = [self.n_steps - sim.steps, self.frames.steps_to_next(sim.steps, sim.dt)]
        if report_every:
            steps.append(report_every - sim.steps % report_every)
        if self.grid is not None:
            steps.append(self.grid.steps_to_next(sim.steps, sim.dt))
        return min(steps)


def _finish(summary: RunSummary, run: _Run | None, wall: float, directory: Path) -> None:
    """Judge the ledger of a completed run, close the recorders and write summary.json (whole,
    by a rename)."""
    sim = None if run is None else run.sim
    if run is not None and run.sim.meter is not None:
        ledger = run.sim.energy()
        summary.energy = asdict(ledger)
        if summary.status == COMPLETED:
            judge_ledger(summary, run.ledger_tolerance, run.remedy)
    for recorder in [] if run is None else run.recorders:
        try:
            recorder.close(complete=summary.status in FINISHED)
        except Exception as exc:  # summary.json must still be written
            summary.warnings.append(f"{type(recorder).__name__}.close failed: {exc}")
    summary.wall_time = wall
    if sim is not None:
        summary.steps, summary.simulated_time = sim.steps, sim.time
        summary.steps_per_second = sim.steps / wall if wall > 0 else 0.0
        summary.impacts = len(sim.impacts)
        speeds = np.hypot(*sim.granule_velocities().reshape(-1, 2).T)
        if speeds.size:
            summary.speeds = {"mean": float(speeds.mean()), "max": float(speeds.max())}
        summary.threads = sim.contacts.threads
        asked = sim.spec.contact_model.threads
        if asked is not None and summary.threads < asked:
            summary.warnings.append(
                f"solver.threads = {asked} asked, {summary.threads} used: no more threads than "
                "free cores"
            )
        process = sim.spec.process
        if process.feed or process.outlet or process.damage or sim.spec.has_bonds:
            frame = sim.frame(contacts=False)
            summary.population = {
                "fed": frame.fed,
                "released": frame.released,
                "departed": frame.departed,
                "broken": 0 if sim.damage is None else len(sim.damage.broken),
                "removed_broken": frame.removed_broken,
                "present": len(frame.granules.ids),
            }
    data = _finite_or_null(asdict(summary))
    text = json.dumps(data, indent=2, allow_nan=False, ensure_ascii=False) + "\n"
    temporary = directory / ".summary.json.tmp"  # written whole, then renamed over the old one
    temporary.write_text(text, encoding="utf-8")
    temporary.replace(directory / "summary.json")


def _smaller_steps(case: Case) -> str:
    """How to take smaller steps in ``case``: the remedy for a ledger that does not close."""
    model = case.contact_model
    if not model.soft:
        return "take smaller steps (solver.dt, or solver.substeps)"
    if model.granule_substeps > 1:
        return (
            "take smaller machine steps (contact_model.granule_substeps = 1: the hammers keep "
            "their velocity through the granules' substeps, and that split's error grows with "
            "how hard they are stopped)"
        )
    return "take smaller steps (contact_model.steps_per_contact, or solver.dt)"


def judge_ledger(summary: RunSummary, tolerance: float, remedy: str) -> None:
    """A completed run whose ledger (``summary.energy``) closes beyond ``tolerance`` (or not at
    all: NaN) becomes :data:`LEDGER_OFF`, its reason saying by how much and what to do
    (``remedy``)."""
    if abs(summary.energy["closure"]) <= tolerance:
        return
    summary.status = LEDGER_OFF
    summary.reason = (
        f"the energy ledger closes to {ledger_closure_text(summary.energy)}, beyond "
        f"solver.ledger_tolerance = "
        f"{tolerance:.3g} ({tolerance:.2%}): {remedy}; or, the cause known, accept it with a "
        "larger solver.ledger_tolerance"
    )


def ledger_closure_text(energy: dict[str, float]) -> str:
    """The closure of a ledger (an :class:`~perga.model.records.EnergyLedger` as a dict) in
    words: "+0.46 % of the 4.01 J in play (residual +0.0184 J)"."""
    return (
        f"{energy['closure']:+.2%} of the {energy['energy_in_play']:.3g} J in play "
        f"(residual {energy['residual']:+.3g} J)"
    )


def _finite_or_null(value: object) -> object:
    """``value`` with every non-finite float replaced by None (null: strict JSON has no
    Infinity or NaN; e.g. a rigid run's contact_duration, which no soft contact bounds)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_null(v) for v in value]
    return value
