"""The runs of ``perga compare --paper``: the bundled paper cases and the sweeps of the paper's
Fig. 3 and 4a, each a bundled case file with ``KEY=VALUE`` overrides (as ``perga run --set``).

They run as study jobs (:mod:`perga.studies.jobs`) on Dask (:mod:`perga.studies.executor`):
each into the directory its key names, and a run found finished is not run again. Each run
keeps its name (``hinged-M5g``, ``blade-w1-f0.3``): the analysis
(:mod:`perga.studies.compare`) and the report name its rows by it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from distributed import Client

from perga.analytic.sliding import BladeSlide
from perga.case import load_case
from perga.run import LEDGER_OFF
from perga.stats.tables import Run, load_run
from perga.studies.executor import BatchCluster, Progress, run_missing
from perga.studies.jobs import Job, make_job

RECORD = 'output.record=["granules", "hammers", "impacts", "energy"]'
"""The tables of a run whose case file names none: the CSV tables, no ParaView series."""
FITTED_GRANULE_MASS = 0.0037581580314
"""kg: the fitted granule of cases/paper-fitted.toml (its efficiency claims as fractions)."""
HAMMER_MASSES = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2)
"""kg: Fig. 4a's range, 5-200 g."""
BLADE_OMEGA_FACTORS = (0.5, 1.0, 2.0, 3.0)
"""× the fitted ω: Fig. 3's ω axis (as perga paper-check's grid, 0.5-3 ω)."""
BLADE_FRICTIONS = (0.1, 0.3, 0.5, 0.8)
"""Fig. 3's f axis (as perga paper-check's grid, 0.1-0.8)."""
SEED = 0
"""solver.seed of every run: the schema's default, so that a run is its case file's own."""
USABLE = ("ok", LEDGER_OFF)
"""Job statuses of a run that reached its end (with its energy ledger off, too)."""


@dataclass(frozen=True)
class PaperRun:
    """One run of the paper study: its name, the bundled case file it starts from (a file name
    in the cases folder) and the ``KEY=VALUE`` overrides on that file."""

    name: str
    case: str
    overrides: tuple[str, ...] = ()


class PaperRunsFailedError(Exception):
    """Runs of the paper study that did not reach their end, each named with its reason."""

    def __init__(self, failed: list[str]) -> None:
        super().__init__("; ".join(failed))
        self.failed = failed


def paper_jobs(cases: Path) -> list[PaperRun]:
    """The runs the paper report needs, on the bundled case files in ``cases``."""
    runs = [
        PaperRun("paper-decaying-branch", "paper-decaying-branch.toml"),
        PaperRun("single-granule", "single-granule.toml", (RECORD,)),
        PaperRun("four-impacts", "four-impacts.toml"),
    ]
    for M in HAMMER_MASSES:
        for m in (0.00016, FITTED_GRANULE_MASS):
            name = f"two-body-M{M * 1e3:g}g-m{m * 1e3:.3g}g"
            masses = (f"hammers.mass={M!r}", f"granules.mass={m!r}")
            runs.append(PaperRun(name, "two-body-impact.toml", masses))
        hinged = (RECORD, f"hammers.mass={M!r}", "solver.duration=0.03")
        runs.append(PaperRun(f"hinged-M{M * 1e3:g}g", "single-granule.toml", hinged))
    return runs + _blade_runs(cases / "blade-exit.toml")


def _blade_runs(path: Path) -> list[PaperRun]:
    """The Fig. 3 sweep: blade-exit.toml over ω and f (the face's and the floor's), the start
    relative to the blade kept, each run 10 % and 2 ms longer than the blade model's exit."""
    case = load_case(path)
    tip = case.hammers.shape.length - case.hammers.shape.hinge_offset
    omega0 = case.rotor.angular_velocity
    (p,), (v,) = case.granules.placement.positions, case.granules.placement.velocities
    h = p[1]
    u0 = v[0] + omega0 * h  # x' relative to the blade at the start, m/s
    runs = []
    for k in BLADE_OMEGA_FACTORS:
        w = k * omega0
        velocity = (u0 - w * h, w * p[0])
        for f in BLADE_FRICTIONS:
            slide = BladeSlide(w, f, f, "corotating", "leading", offset=h, tip=tip)
            t_exit = float(slide.integrate(p[0], u0, 10.0).t[-1])
            overrides = (
                f"rotor.omega={w!r}",
                f"contacts.granule-hammer.friction={f!r}",
                f"effects.floor_friction.friction={f!r}",
                f"solver.duration={1.1 * t_exit + 2e-3!r}",
                f"granules.placement.velocities=[[{velocity[0]!r}, {velocity[1]!r}]]",
            )
            runs.append(PaperRun(f"blade-w{k:g}-f{f:g}", path.name, overrides))
    return runs


def paper_job(run: PaperRun, cases: Path, work: Path) -> Job:
    """The study job of ``run``: its case in ``cases``, its run directory ``work/runs/KEY``."""
    return make_job(cases / run.case, {}, 0, SEED, (), work, extra=run.overrides)


def run_paper_study(
    cases: Path,
    work: Path,
    *,
    client: Client | None = None,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
) -> list[Run]:
    """Run what the paper study still lacks into ``work`` (on ``client``, the cluster at
    ``scheduler`` or a local cluster of ``workers`` processes; a failed run again only with
    ``retry_failed``) and load every run under its name. :class:`PaperRunsFailedError` names the
    runs that did not reach their end."""
    runs = paper_jobs(cases)
    jobs = [paper_job(run, cases, work) for run in runs]
    rows: dict[str, dict[str, Any]] = {}
    unique = list({job.key: job for job in jobs}.values())
    run_missing(
        unique,
        lambda row: rows.__setitem__(row["key"], row),
        client=client,
        scheduler=scheduler,
        workers=workers,
        retry_failed=retry_failed,
        progress=progress,
    )
    failed = [
        f"{run.name} ({job.directory}): {rows[job.key]['reason']}"
        for run, job in zip(runs, jobs, strict=True)
        if rows[job.key]["status"] not in USABLE
    ]
    if failed:
        raise PaperRunsFailedError(failed)
    return [load_run(job.directory, run.name) for run, job in zip(runs, jobs, strict=True)]
