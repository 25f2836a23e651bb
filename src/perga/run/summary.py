"""What ``summary.json`` holds and how it is written: the run's status and reason, its steps and
plans, the counts, speeds and ledger at the end (from the system and the last frame), written
whole by a rename whatever ended the run."""

from __future__ import annotations

import json
import math
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

from perga.model.frame import Frame
from perga.model.system import System

COMPLETED = "completed"
LEDGER_OFF = "completed, ledger off"
"""The status of a run that reached its end with its energy ledger's closure beyond
``solver.ledger_tolerance``: its results are all there, but not to be trusted as they are."""
FINISHED = (COMPLETED, LEDGER_OFF)
"""The statuses of a run that reached its end (nothing to resume)."""


@dataclass
class RunSummary:
    """What summary.json holds (SI units)."""

    case: str
    """The case file run; summary.json names it from the run directory (:func:`path_from`)."""
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
    half-period of a sticking contact with its steps (:class:`perga.model.plan.PairPlan`)."""
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


def describe_end(summary: RunSummary, frame: Frame, system: System, threads: int) -> None:
    """The summary's steps, times, counts, speeds, threads and population from the frame at
    the end of the run and the ``system`` it ran."""
    summary.steps, summary.simulated_time = frame.step, frame.time
    summary.steps_per_second = frame.step / summary.wall_time if summary.wall_time > 0 else 0.0
    summary.impacts = frame.impacts
    speeds = frame.granules.speeds
    if speeds.size:
        summary.speeds = {"mean": float(speeds.mean()), "max": float(speeds.max())}
    summary.threads = threads
    asked = system.contact_model.threads
    if asked is not None and summary.threads < asked:
        summary.warnings.append(
            f"solver.threads = {asked} asked, {summary.threads} used: no more threads than "
            "free cores"
        )
    process = system.process
    if process.feed or process.outlet or process.damage or system.has_bonds:
        summary.population = {
            "fed": frame.fed,
            "released": frame.released,
            "departed": frame.departed,
            "broken": frame.broken,
            "removed_broken": frame.removed_broken,
            "present": len(frame.granules.ids),
        }


def smaller_steps(system: System) -> str:
    """How to take smaller steps in ``system``: the remedy for a ledger that does not close."""
    model = system.contact_model
    if model.kind == "rigid":
        return "take smaller steps (solver.dt, or solver.substeps)"
    if model.substeps > 1:
        return (
            "take smaller steps (contact_model.steps_per_contact, solver.dt, or fewer "
            "contact_model.granule_substeps: the machine's own forces, hinges and drive, act "
            "once per machine step)"
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


def finite_or_null(value: object) -> object:
    """``value`` with every non-finite float replaced by None (null: strict JSON has no
    Infinity or NaN; e.g. a rigid run's contact_duration, which no soft contact bounds)."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [finite_or_null(v) for v in value]
    return value


def path_from(directory: Path, path: str | Path) -> str:
    """``path`` as seen from ``directory``, so that the two can move together: relative (``/``
    between parts), or the file's name where no relative path leads to it (another drive)."""
    try:
        return Path(os.path.relpath(Path(path).resolve(), directory.resolve())).as_posix()
    except ValueError:
        return Path(path).name


def write_summary(summary: RunSummary, directory: Path) -> None:
    """``directory``/summary.json: strict JSON (non-finite floats as null), the case named
    from ``directory`` (:func:`path_from`), written whole to a temporary file and renamed over
    the old one."""
    data = finite_or_null(asdict(summary) | {"case": path_from(directory, summary.case)})
    text = json.dumps(data, indent=2, allow_nan=False, ensure_ascii=False) + "\n"
    temporary = directory / ".summary.json.tmp"
    temporary.write_text(text, encoding="utf-8")
    temporary.replace(directory / "summary.json")
