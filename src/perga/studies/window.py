"""``perga window``: the operating window of a case over two keys (e.g. rotor speed and hammer
mass), run as a sweep (:mod:`perga.studies.sweep`) on Dask.

Every grid point runs ``replicates`` times, each replicate with its own ``solver.seed``, and
gives the four process metrics of :mod:`perga.stats.metrics`: ``released_fraction`` (-),
``damaged_fraction`` (-), ``throughput`` (kg/s) and ``energy_per_kg`` (J/kg). The window table
holds, per point, the mean and standard deviation over replicates (ddof 1) of each; a point is
inside the window when release_mean ≥ the release target and damage_mean ≤ the damage limit.
The best point is the one inside with the highest throughput, ties by the lower energy per kg;
with none inside, the nearest (the smallest shortfall from the target plus excess over the
limit) is named instead.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from perga.studies.design import axis
from perga.studies.executor import BatchCluster, Progress
from perga.studies.jobs import toml_value
from perga.studies.pareto import pareto_front
from perga.studies.study_file import Study, StudyError, study_from_options
from perga.studies.sweep import sweep

METRICS = ("released_fraction", "damaged_fraction", "throughput", "energy_per_kg")
"""The window's metrics, in their order in the table."""
RELEASE, DAMAGE, THROUGHPUT, ENERGY = METRICS
LEDGER = "ledger_closure"
"""Also kept per run (a run whose ledger misses its case's tolerance is not "ok": the runner's
status "completed, ledger off", with its reason among its point's notes)."""
WINDOW_OBJECTIVES = {THROUGHPUT: "max", DAMAGE: "min", ENERGY: "min"}
"""The trade-offs: throughput (kg/s) up, damaged fraction (-) and energy per kg (J/kg) down."""
SPEED_KEYS = ("rotor.rpm", "rotor.omega")
"""Keys whose axis is the speed axis of the trend checks."""
TABLE = "window.parquet"


@dataclass(frozen=True)
class WindowStudy:
    """A window study: the sweep behind it, its two axes (case keys; ``axes[0]`` on the
    maps' x axis) and the limits: release fraction ≥ ``release_target``, damage fraction ≤
    ``damage_limit`` (both -)."""

    study: Study
    axes: tuple[str, str]
    release_target: float
    damage_limit: float

    @property
    def speed_axis(self) -> str:
        """The axis the trends are checked along: a rotor speed key, else the first axis."""
        return next((k for k in self.axes if k in SPEED_KEYS), self.axes[0])

    def grid(self) -> tuple[list[float], list[float]]:
        """The values of each axis, ascending."""
        xs, ys = (sorted(float(v) for v in axis(self.study.parameters[k])) for k in self.axes)
        return xs, ys


def window_study(
    case: Path,
    sets: list[str],
    *,
    replicates: int = 2,
    seed: int = 0,
    release_target: float = 0.9,
    damage_limit: float = 0.05,
) -> WindowStudy:
    """The study of ``perga window CASE --set K1=A:B:N --set K2=A:B:N [--set KEY=VALUE ...]``:
    exactly two keys with several values (the axes), the others fixed; checked like a sweep's
    options (StudyError naming each bad option)."""
    problems = []
    for name, value in (("--release-target", release_target), ("--damage-limit", damage_limit)):
        if not (math.isfinite(value) and 0.0 <= value <= 1.0):
            problems.append(f"{name}: a fraction in [0, 1] (got {value:g})")
    if not 1 <= replicates <= 1000:
        problems.append(f"--replicates: runs per point, in [1, 1000] (got {replicates})")
    if seed < 0:
        problems.append(f"--seed: a seed >= 0 (got {seed})")
    for text in sets:
        if text.partition("=")[0].strip() == "solver.seed":
            problems.append(f"--set {text}: the replicates' seeds come from --seed")
    try:
        study = study_from_options(case, sets, [*METRICS, LEDGER], max(1, replicates), max(0, seed))
    except StudyError as exc:
        problems += exc.problems
        study = None
    axes: list[str] = []
    if study is not None:
        axes = [k for k, p in study.parameters.items() if len(axis(p)) > 1]
        if len(axes) != 2:
            named = ", ".join(axes) or "none"
            problems.append(
                f"--set: give exactly two keys with several values (KEY=LO:HI:N, N >= 2), "
                f"the window's axes; got {len(axes)} ({named})"
            )
    if problems:
        raise StudyError(problems)
    assert study is not None
    return WindowStudy(study, (axes[0], axes[1]), release_target, damage_limit)


@dataclass(frozen=True)
class Point:
    """One grid point of the window table: its axis values, runs, and each metric's mean and
    standard deviation over the replicates that gave it (nan if none; sd nan with one)."""

    x: float
    y: float
    runs: int
    failed: int
    mean: dict[str, float]
    sd: dict[str, float]
    count: dict[str, int]
    notes: list[str] = field(default_factory=list)


def _stats(values: list[float]) -> tuple[float, float, int]:
    finite = np.array([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if finite.size == 0:
        return math.nan, math.nan, 0
    sd = float(np.std(finite, ddof=1)) if finite.size > 1 else math.nan
    return float(np.mean(finite)), sd, int(finite.size)


def aggregate(
    rows: list[dict[str, Any]], axes: tuple[str, str], grid: tuple[list[float], list[float]]
) -> list[Point]:
    """The sweep's rows (one per run) reduced to one point per grid cell, x fastest. Only rows
    with status "ok" count; a metric a run could not give (nan) is left out of its mean."""
    points = []
    for y, x in itertools.product(grid[1], grid[0]):
        cell = [r for r in rows if r.get(axes[0]) == x and r.get(axes[1]) == y]
        ok = [r for r in cell if r.get("status") == "ok"]
        mean, sd, count = {}, {}, {}
        for m in METRICS:
            mean[m], sd[m], count[m] = _stats([_float(r.get(m)) for r in ok])
        notes = sorted({str(r.get("notes")) for r in ok if r.get("notes")})
        notes += sorted({str(r.get("reason")) for r in cell if r.get("status") != "ok"})
        points.append(Point(x, y, len(cell), len(cell) - len(ok), mean, sd, count, notes))
    return points


def _float(value: Any) -> float:
    try:
        return math.nan if value is None else float(value)
    except (TypeError, ValueError):
        return math.nan


def inside(release: float, damage: float, release_target: float, damage_limit: float) -> bool:
    """Whether a point meets both: release ≥ target and damage ≤ limit (nan: it does not)."""
    return bool(release >= release_target and damage <= damage_limit)


def in_window(point: Point, release_target: float, damage_limit: float, shift: float = 0.0) -> bool:
    """Whether ``point`` is inside the window with each mean moved by ``shift`` standard
    deviations towards failing (shift > 0: the pessimistic window; < 0: the optimistic one;
    a missing sd counts as 0)."""
    r_sd = 0.0 if math.isnan(point.sd[RELEASE]) else point.sd[RELEASE]
    d_sd = 0.0 if math.isnan(point.sd[DAMAGE]) else point.sd[DAMAGE]
    return inside(
        point.mean[RELEASE] - shift * r_sd,
        point.mean[DAMAGE] + shift * d_sd,
        release_target,
        damage_limit,
    )


def shortfall(point: Point, release_target: float, damage_limit: float) -> float:
    """How far a point is from the window: release short of the target plus damage over the
    limit (both -; 0 inside, inf if either mean is missing)."""
    r, d = point.mean[RELEASE], point.mean[DAMAGE]
    if math.isnan(r) or math.isnan(d):
        return math.inf
    return max(0.0, release_target - r) + max(0.0, d - damage_limit)


@dataclass(frozen=True)
class Best:
    """The chosen point and whether it is inside the window (else it is the nearest)."""

    point: Point | None
    inside: bool


def best_point(points: list[Point], release_target: float, damage_limit: float) -> Best:
    """The point inside the window with the highest throughput mean, ties by the lower
    energy_per_kg mean (a missing value ranks last); with none inside, the nearest one
    (:func:`shortfall`), ties by the same rule; ``Best(None, False)`` if no point has both
    means."""

    def rank(p: Point) -> tuple[float, float]:
        t, e = p.mean[THROUGHPUT], p.mean[ENERGY]
        return (-t if math.isfinite(t) else math.inf, e if math.isfinite(e) else math.inf)

    candidates = [p for p in points if in_window(p, release_target, damage_limit)]
    if candidates:
        return Best(min(candidates, key=rank), True)
    near = [p for p in points if math.isfinite(shortfall(p, release_target, damage_limit))]
    if not near:
        return Best(None, False)
    return Best(
        min(near, key=lambda p: (shortfall(p, release_target, damage_limit), *rank(p))), False
    )


@dataclass(frozen=True)
class Trend:
    """A metric along the speed axis at one value of the other axis: pairs of speeds (i < j)
    where the mean rose, fell or stayed equal, those that rose or fell by more than the
    replicates' spread (√(sd_i² + sd_j²)), and Spearman's ρ (nan if undefined)."""

    metric: str
    other: float
    pairs: int
    rising: int
    falling: int
    equal: int
    rising_clear: int
    falling_clear: int
    rho: float


def trend(
    speeds: list[float], means: list[float], sds: list[float], metric: str, other: float
) -> Trend:
    """The :class:`Trend` of ``means`` (with ``sds``) over ``speeds``; points without a mean
    are left out."""
    data = sorted(
        (s, m, 0.0 if math.isnan(d) else d)
        for s, m, d in zip(speeds, means, sds, strict=True)
        if math.isfinite(m)
    )
    rising = falling = equal = rising_clear = falling_clear = 0
    for (_, mi, di), (_, mj, dj) in itertools.combinations(data, 2):
        spread = math.hypot(di, dj)
        if mj > mi:
            rising += 1
            rising_clear += mj - mi > spread
        elif mj < mi:
            falling += 1
            falling_clear += mi - mj > spread
        else:
            equal += 1
    rho = math.nan
    values = [m for _, m, _ in data]
    if len(data) >= 2 and len(set(values)) > 1:
        from scipy.stats import spearmanr

        rho = float(spearmanr([s for s, _, _ in data], values).statistic)
    pairs = rising + falling + equal
    return Trend(metric, other, pairs, rising, falling, equal, rising_clear, falling_clear, rho)


def trends(window: WindowStudy, points: list[Point]) -> list[Trend]:
    """Damage and release along the speed axis, one :class:`Trend` each per value of the other
    axis."""
    speed = window.speed_axis
    on_x = speed == window.axes[0]
    out = []
    for metric in (DAMAGE, RELEASE):
        others = sorted({p.y if on_x else p.x for p in points})
        for other in others:
            row = [p for p in points if (p.y if on_x else p.x) == other]
            out.append(
                trend(
                    [p.x if on_x else p.y for p in row],
                    [p.mean[metric] for p in row],
                    [p.sd[metric] for p in row],
                    metric,
                    other,
                )
            )
    return out


def fixed_overrides(window: WindowStudy) -> tuple[str, ...]:
    """The study's fixed ``KEY=VALUE`` (its parameters with one value, not an axis)."""
    return tuple(
        f"{k}={toml_value(p.values[0])}"
        for k, p in window.study.parameters.items()
        if k not in window.axes and p.values is not None and len(p.values) == 1
    )


def foundations(window: WindowStudy, calibrated: bool = False) -> list[str]:
    """What a map of ``window`` rests on, as Markdown list items: the contact model with its
    duration and step, the comb's release law with its values, and (unless ``calibrated``:
    a map under a posterior says what it draws) that every material value is the case's."""
    from perga.model.compile import load_system

    case, system = load_system(window.study.case, overrides=fixed_overrides(window))
    model = case.contact_model
    if model.kind == "rigid":
        contacts = f"rigid impulses (Pymunk), step {system.granule_dt * 1e6:.3g} µs"
    else:
        given = (
            f"contact duration {model.duration * 1e3:.3g} ms (contact_model.duration: a "
            "physical value only where a measured stiffness gives it)"
            if model.duration is not None
            else "stiffness from contact_model.stiffness or the materials' moduli"
        )
        step = f"granule step {system.granule_dt * 1e6:.3g} µs"
        contacts = f"soft {model.kind} contacts, {given}, {step}"
    material = case.materials[case.granules.material]
    if material.detachment_force is None:
        release = "no bonds: no granule is held"
    elif material.detachment_energy is not None:
        release = (
            f"a blow must leave a held granule more than detachment_energy = "
            f"{material.detachment_energy:g} J (a blow begins above detachment_force = "
            f"{material.detachment_force:g} N): the same outcome whatever the contact's "
            "stiffness or the step"
        )
    else:
        release = (
            f"the force law, detachment_force = {material.detachment_force:g} N: at an impact "
            "the force is set by the contact's stiffness (soft) or the step (rigid), so the "
            "release depends on the numerics"
        )
    lines = [f"- contacts: {contacts}", f"- release from the comb: {release}"]
    if not calibrated:
        lines.append(
            "- every material and contact value is the case's own, none calibrated (the "
            "case's description gives each one's source); `perga window --posterior` carries "
            "a calibration's uncertainty into the map"
        )
    return lines


def table_columns(window: WindowStudy, points: list[Point]) -> dict[str, list[Any]]:
    """The window table as columns: the two axes, runs and failed runs, each metric's mean,
    sd and number of runs that gave it, and the window (nominal, pessimistic: means moved 1 sd
    towards failing, optimistic: 1 sd the other way)."""
    rt, dl = window.release_target, window.damage_limit
    columns: dict[str, list[Any]] = {
        window.axes[0]: [p.x for p in points],
        window.axes[1]: [p.y for p in points],
        "runs": [p.runs for p in points],
        "failed": [p.failed for p in points],
    }
    for m in METRICS:
        columns[f"{m}_mean"] = [p.mean[m] for p in points]
        columns[f"{m}_sd"] = [p.sd[m] for p in points]
        columns[f"{m}_n"] = [p.count[m] for p in points]
    columns["in_window"] = [in_window(p, rt, dl) for p in points]
    columns["in_window_pessimistic"] = [in_window(p, rt, dl, 1.0) for p in points]
    columns["in_window_optimistic"] = [in_window(p, rt, dl, -1.0) for p in points]
    columns["notes"] = ["; ".join(p.notes) for p in points]
    return columns


def write_window_table(columns: dict[str, list[Any]], directory: Path) -> tuple[Path, Path]:
    """The window table as ``DIR/window.parquet`` and ``DIR/window.csv``."""
    table = pa.table(columns)
    parquet, csv = directory / TABLE, directory / "window.csv"
    pq.write_table(table, parquet)
    pacsv.write_csv(table, csv)
    return parquet, csv


def trade_offs(points: list[Point]) -> list[Point]:
    """The points no other beats on every one of throughput (more), damage and energy per kg
    (less): the Pareto front a designer chooses from (:func:`perga.studies.pareto.pareto_front`;
    a point missing one of the three is never on it)."""
    values = np.array([[p.mean[m] for m in WINDOW_OBJECTIVES] for p in points]).reshape(-1, 3)
    return [points[i] for i in pareto_front(values, list(WINDOW_OBJECTIVES.values()))]


@dataclass(frozen=True)
class WindowResult:
    """A finished window study: its points, best point, Pareto front (:func:`trade_offs`),
    trends and the sweep's rows and counts, for the maps and report
    (:mod:`perga.studies.window_report`)."""

    window: WindowStudy
    points: list[Point]
    best: Best
    front: list[Point]
    trends: list[Trend]
    foundations: list[str]
    rows: list[dict[str, Any]]
    ran: int
    reused: int
    failed: int


def run_window(
    window: WindowStudy,
    directory: Path,
    *,
    scheduler: str | BatchCluster | None = None,
    workers: int | None = None,
    retry_failed: bool = False,
    progress: Progress | None = None,
) -> WindowResult:
    """Run the window's sweep into ``directory`` (runs in ``DIR/runs``, one row each in
    ``DIR/results.parquet``), then write the window table (``DIR/window.parquet``, .csv)."""
    result = sweep(
        window.study,
        directory,
        scheduler=scheduler,
        workers=workers,
        retry_failed=retry_failed,
        progress=progress,
    )
    points = aggregate(result.rows, window.axes, window.grid())
    best = best_point(points, window.release_target, window.damage_limit)
    found = trends(window, points)
    write_window_table(table_columns(window, points), directory)
    return WindowResult(
        window, points, best, trade_offs(points), found, foundations(window), result.rows,
        result.ran, result.reused, result.failed,
    )  # fmt: skip
