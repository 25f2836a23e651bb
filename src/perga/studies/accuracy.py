"""``perga accuracy``: what accuracy costs in time, as work-precision data.

For each scene of :mod:`perga.studies.accuracy_scenes` and each :class:`Setting` of the grid
(rigid: time step × solver iterations; linear and Hertz soft contacts: steps per contact ×
granule substeps) one run through the case path (``Case`` -> ``compile_case`` -> ``Simulation``,
impact log and energy meter on, as ``perga run`` records them) gives:

* the error against the scene's reference (:data:`REFERENCES`), deterministic;
* the wall time per simulated second: the time spent stepping (``perf_counter``
  around each call; measuring and building excluded) over the simulated time; the median over
  ``repeats`` runs where one run is cheap.

Errors (dimensionless, relative): restitution |e_sim/e − 1|; blade exit speed |v/v_exact − 1|;
hinged impact |v_g − v_g,exact|/|v_g,exact|; trajectory max_t |y(t) − y_ref(t)|/drop height;
energy ledger |closure| (:mod:`perga.machine.energy`).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from perga.analytic.common import STANDARD_GRAVITY
from perga.case import Case, CaseError
from perga.engine.simulation import Simulation
from perga.model.system import System
from perga.studies.accuracy_scenes import (
    BOUNCE,
    BounceReference,
    Scene,
    Setting,
    blade_exit_reference,
    blade_scene,
    bounce_scene,
    hinged_reference,
    hinged_scene,
    restitution_scene,
)

LEVELS = (0.1, 0.01, 0.001)
"""Error levels of the recommended-settings table: 10 %, 1 %, 0.1 %."""

REFERENCES = {
    "restitution": "restitution on a flat face, |e_sim/e − 1|",
    "blade": "exit speed from a frictionless blade, |v/v_exact − 1|",
    "hinged": "hinged hammer strikes a granule: |Δv_g|/|v_g|",
    "trajectory": "height after 4 successive impacts, max|Δy|/drop",
    "energy": "energy-ledger closure (hinged impact), |closure|",
}
"""Reference name -> what its error measures."""

CHEAP = 1.0
"""s: a run whose stepping took less than this is repeated for the median wall time."""


@dataclass(frozen=True)
class Row:
    """One cell group of the table: a setting's error against one reference and its cost.

    dt: granule step, s; machine_dt: Pymunk step, s; t_c: shortest soft contact, s (inf rigid);
    error: dimensionless (nan when the run failed or was refused); wall_per_sim: wall s per
    simulated s (nan when not run); steps: Pymunk steps; status: 'ok', 'refused: ...' (the case
    checks) or 'failed: ...'.
    """

    reference: str
    model: str
    family: str
    setting: str
    dt: float
    machine_dt: float
    t_c: float
    iterations: int
    steps_per_contact: float
    granule_substeps: int
    error: float
    wall_per_sim: float
    steps: int
    status: str = "ok"


@dataclass
class Measured:
    """What one run measured: errors by reference, stepping wall time (s), simulated time (s),
    steps."""

    errors: dict[str, float]
    wall: float
    simulated: float
    steps: int


class Stepper:
    """Steps a simulation and adds the wall time of each call."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.wall = 0.0

    def step(self) -> None:
        """One timed step."""
        start = time.perf_counter()
        self.sim.step()
        self.wall += time.perf_counter() - start

    def run_to(self, steps: int) -> None:
        """Timed steps until the simulation has taken ``steps`` in all, as a run takes them
        (``Simulation.advance_to``: whole steps compiled where the case allows)."""
        sim = self.sim
        start = time.perf_counter()
        with sim.running():
            sim.advance_to(steps)
        self.wall += time.perf_counter() - start


def simulation(system: System) -> Simulation:
    """The rigid or soft simulation of a case, impact log and energy meter on."""
    return Simulation(system)


def _run_to(stepper: Stepper, duration: float) -> None:
    stepper.run_to(math.ceil(duration / stepper.sim.dt - 1e-9))


def _finish(stepper: Stepper, errors: dict[str, float]) -> Measured:
    sim = stepper.sim
    return Measured(errors, stepper.wall, sim.time, sim.steps)


def measure_restitution(case: Case, system: System, duration: float) -> Measured:
    """e = −(rebound normal speed)/(approach normal speed) relative to the face's material point
    (it turns at the schema's smallest ω: 5e-8 m/s, which would show as 6e-8 in e), read at the
    end of the run, when the granule flies free again; the face's normal is +y."""
    stepper = Stepper(simulation(system))
    (v_in,) = np.array(case.granules.placement.velocities, dtype=float)
    _run_to(stepper, duration)
    granules = stepper.sim.frame(contacts=False).granules
    x = float(granules.positions[0, 0])
    face = case.rotor.angular_velocity * x  # ω ẑ × r, its y component (r_y ≪ r_x, ω tiny)
    e_sim = -(float(granules.velocities[0, 1]) - face) / (float(v_in[1]) - face)
    e = case.granule_hammer_contact.restitution
    return _finish(stepper, {"restitution": abs(e_sim / e - 1.0)})


def _along_blade(sim: Simulation, omega: float) -> tuple[float, float]:
    """Granule 0's coordinate along the blade (m) and its velocity relative to the blade along
    it (m/s)."""
    frame = sim.frame(contacts=False)
    theta = frame.machine.rotor_angle
    ex = np.array([math.cos(theta), math.sin(theta)])
    p, v = frame.granules.positions[0], frame.granules.velocities[0]
    v_rel = v - omega * np.array([-p[1], p[0]])
    return float(p @ ex), float(v_rel @ ex)


def measure_blade(case: Case, system: System, duration: float) -> Measured:
    """Exit speed relative to the blade at the tip, interpolated linearly between the two steps
    around the crossing."""
    omega = case.rotor.angular_velocity
    tip = case.hammers.hinge_radius + case.hammers.shape.length
    stepper = Stepper(simulation(system))
    sim = stepper.sim
    x0, v0 = _along_blade(sim, omega)
    _, v_exact = blade_exit_reference()
    while sim.time < duration:
        stepper.step()
        x1, v1 = _along_blade(sim, omega)
        if x1 >= tip:
            v = v0 + (tip - x0) / (x1 - x0) * (v1 - v0)
            return _finish(stepper, {"blade": abs(v / v_exact - 1.0)})
        x0, v0 = x1, v1
    return _finish(stepper, {"blade": math.nan})


def measure_hinged(case: Case, system: System, duration: float) -> Measured:
    """Granule velocity at the end (free flight after the impact) against the instantaneous
    impact, and the ledger's closure over the run."""
    stepper = Stepper(simulation(system))
    _run_to(stepper, duration)
    sim = stepper.sim
    exact = hinged_reference(case)
    v = sim.frame(contacts=False).granules.velocities[0]
    error = float(np.hypot(*(v - exact)) / np.hypot(*exact))
    return _finish(stepper, {"hinged": error, "energy": abs(sim.energy().closure)})


_BOUNCE_REFERENCES: dict[tuple[str, float], BounceReference] = {}


def _bounce_reference(case: Case, duration: float) -> BounceReference:
    """The model's bounce reference (one per contact model: the soft law does not depend on the
    step settings)."""
    key = (case.contact_model.kind, duration)
    if key not in _BOUNCE_REFERENCES:
        _BOUNCE_REFERENCES[key] = BounceReference(case, 1.01 * duration)
    return _BOUNCE_REFERENCES[key]


def measure_bounce(case: Case, system: System, duration: float) -> Measured:
    """Largest height error over the run (every step) relative to the drop height."""
    reference = _bounce_reference(case, duration)
    stepper = Stepper(simulation(system))
    sim = stepper.sim
    worst = 0.0
    for _ in range(math.ceil(duration / sim.dt - 1e-9)):
        stepper.step()
        y = float(sim.frame(contacts=False).granules.positions[0, 1])
        worst = max(worst, abs(y - reference.height(sim.time)))
    return _finish(stepper, {"trajectory": worst / BOUNCE["drop"]})


@dataclass(frozen=True)
class Study:
    """A scene, how to measure it, and its settings grid."""

    scene: Scene
    measure: Callable[[Case, System, float], Measured]
    settings: tuple[Setting, ...]


def _rigid(dts: Sequence[float], iterations: Sequence[int]) -> list[Setting]:
    """Rigid settings: every time step (s) at every iteration count."""
    return [Setting("rigid", dt=dt, iterations=i) for i in iterations for dt in dts]


def _soft(
    steps_per_contact: Sequence[float], substeps: int, contact_duration: float = 1e-4
) -> list[Setting]:
    """Linear and Hertz settings: every steps_per_contact at ``substeps`` granule substeps."""
    return [
        Setting(
            model,  # type: ignore[arg-type]
            steps_per_contact=n,
            granule_substeps=substeps,
            contact_duration=contact_duration,
        )
        for model in ("linear", "hertz")
        for n in steps_per_contact
    ]


def studies(quick: bool = False) -> list[Study]:
    """The study definitions: scenes, measurements and settings grids (``quick``: a small
    subset for tests)."""
    if quick:
        return [
            Study(
                restitution_scene(),
                measure_restitution,
                tuple(_rigid((1e-4, 1e-5), (10,)) + _soft((10, 20, 40), 1)),
            ),
            Study(
                hinged_scene(),
                measure_hinged,
                tuple(_rigid((1e-4, 1e-5), (10,)) + _soft((20, 50), 1)),
            ),
        ]
    spc = (10, 20, 50, 100, 200)
    dts = (1e-4, 3e-5, 1e-5, 3e-6, 1e-6)
    return [
        Study(
            restitution_scene(),
            measure_restitution,
            tuple(_rigid(dts[::2], (10,)) + _soft(spc, 1) + _soft(spc, 10) + _soft(spc, 100)),
        ),
        Study(
            blade_scene(),
            measure_blade,
            tuple(_rigid(dts, (3, 10, 30)) + _soft(spc, 1) + _soft(spc, 10)),
        ),
        Study(
            hinged_scene(),
            measure_hinged,
            tuple(
                _rigid(dts, (3, 10, 30))
                + _soft(spc, 1)
                + _soft(spc, 10)
                + _soft(spc, 1, contact_duration=2e-5)
            ),
        ),
        Study(
            bounce_scene(STANDARD_GRAVITY),
            measure_bounce,
            tuple(
                _rigid(tuple(10 * dt for dt in dts), (10,))
                + _soft(spc[:3], 1)
                + _soft(spc, 10)
                + _soft(spc, 100)
            ),
        ),
    ]


def _rows(
    study: Study, setting: Setting, case: Case | None, measured: Measured | None, status: str
) -> list[Row]:
    """Rows of one setting: one per reference the study measures."""
    references = measured.errors if measured else _references_of(study)
    spec_dt = machine = t_c = math.nan
    if case is not None:
        from perga.model.plan import step_plan

        plan = step_plan(case)
        spec_dt, machine, t_c = plan.granule, plan.machine, plan.contact_duration
    return [
        Row(
            reference=name,
            model=setting.model,
            family=setting.family,
            setting=setting.label,
            dt=spec_dt,
            machine_dt=machine,
            t_c=t_c,
            iterations=setting.iterations,
            steps_per_contact=setting.steps_per_contact if setting.model != "rigid" else math.nan,
            granule_substeps=setting.granule_substeps,
            error=measured.errors[name] if measured else math.nan,
            wall_per_sim=measured.wall / measured.simulated if measured else math.nan,
            steps=measured.steps if measured else 0,
            status=status,
        )
        for name in references
    ]


def _references_of(study: Study) -> list[str]:
    return {
        measure_restitution: ["restitution"],
        measure_blade: ["blade"],
        measure_hinged: ["hinged", "energy"],
        measure_bounce: ["trajectory"],
    }[study.measure]


def run_setting(study: Study, setting: Setting, repeats: int = 3) -> list[Row]:
    """Run one setting (repeated while cheap, median wall time); rows for each reference. A
    setting the case checks refuse, or a run that fails, gives rows with its status."""
    try:
        case, system = study.scene.case(setting)
    except CaseError as exc:
        return _rows(study, setting, None, None, "refused: " + "; ".join(exc.problems))
    try:
        first = study.measure(case, system, study.scene.duration)
        walls = [first.wall]
        while len(walls) < repeats and first.wall < CHEAP:
            again = study.measure(case, system, study.scene.duration)
            if again.errors != first.errors:  # the engines are deterministic
                raise RuntimeError(f"not deterministic: {first.errors} then {again.errors}")
            walls.append(again.wall)
    except Exception as exc:  # a setting that blows up is a result, not a crash
        return _rows(study, setting, case, None, f"failed: {type(exc).__name__}: {exc}")
    return _rows(study, setting, case, replace(first, wall=statistics.median(walls)), "ok")


def warm_up() -> None:
    """Compile (or load from numba's cache) the soft kernels before anything is timed: one
    restitution run per soft model and substep count."""
    scene = restitution_scene()
    for model in ("linear", "hertz"):
        for k in (1, 10):
            setting = Setting(model, steps_per_contact=10, granule_substeps=k)  # type: ignore[arg-type]
            measure_restitution(*scene.case(setting), scene.duration)


@dataclass
class StudyResult:
    """All rows of a study run, its wall time (s) and the machine's load average at start/end."""

    rows: list[Row] = field(default_factory=list)
    wall: float = 0.0
    load: tuple[float, float] = (math.nan, math.nan)


def _load() -> float:
    try:
        import os

        return os.getloadavg()[0]
    except OSError:
        return math.nan


def run_study(
    quick: bool = False,
    repeats: int = 3,
    progress: Callable[[str], None] | None = None,
) -> StudyResult:
    """Every study's settings, in order; ``progress`` gets a line per setting."""
    result = StudyResult()
    start, load0 = time.perf_counter(), _load()
    warm_up()
    for study in studies(quick):
        for setting in study.settings:
            rows = run_setting(study, setting, repeats)
            result.rows += rows
            if progress:
                progress(_progress_line(study.scene.name, setting, rows))
    result.wall = time.perf_counter() - start
    result.load = (load0, _load())
    return result


def _progress_line(scene: str, setting: Setting, rows: Iterable[Row]) -> str:
    parts = [f"{r.reference} {r.error:.3g}" for r in rows]
    row = next(iter(rows))
    cost = f"{row.wall_per_sim:.3g} wall s/sim s" if row.status == "ok" else row.status
    return f"{scene:12s} {setting.label:32s} {', '.join(parts)}; {cost}"


def recommend(rows: Sequence[Row], levels: Sequence[float] = LEVELS) -> list[dict[str, object]]:
    """For each reference and error level the cheapest run setting (lowest wall time per
    simulated second) whose error is at most the level; ``setting`` None when none reaches it.
    Rows without a finite error or cost are ignored."""
    out: list[dict[str, object]] = []
    for reference in dict.fromkeys(r.reference for r in rows):
        candidates = [
            r
            for r in rows
            if r.reference == reference
            and r.status == "ok"
            and math.isfinite(r.error)
            and math.isfinite(r.wall_per_sim)
        ]
        for level in levels:
            good = [r for r in candidates if r.error <= level]
            best = min(good, key=lambda r: r.wall_per_sim) if good else None
            out.append({"reference": reference, "level": level, "row": best})
    return out
