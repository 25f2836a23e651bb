"""perga run with soft contacts: a granule struck by a Pymunk hammer through the whole stack.

The bundled soft single-granule case (a 0.16 g granule, one hinged plate hammer at 600 rpm),
varied: the restitution measured from impacts.csv (−v_n after / v_n before, relative to the
hammer's material point) must equal the pair's e within 0.5 % (the issue's tolerance) at the
automatic step, and the energy ledger must close.
"""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from perga.case import load_case
from perga.run import prepare_directory, run_case

ROOT = Path(__file__).resolve().parents[1]
SOFT = ROOT / "cases" / "soft-single-granule.toml"


def soft_run(tmp_path: Path, *, replace: dict[str, str] | None = None, duration: float = 0.03):
    """Run the soft single-granule case, changed by ``replace`` (text -> text); returns the
    summary and the impacts table."""
    text = SOFT.read_text().replace("duration = 0.2", f"duration = {duration}")
    for old, new in (replace or {}).items():
        assert old in text, old
        text = text.replace(old, new)
    path = tmp_path / "case.toml"
    path.write_text(text)
    out = tmp_path / "run"
    prepare_directory(out, overwrite=True)
    run_case(load_case(path), path, out)
    with (out / "impacts.csv").open() as f:
        impacts = list(csv.DictReader(f))
    return json.loads((out / "summary.json").read_text()), impacts


def restitution(impact: dict[str, str]) -> float:
    return -float(impact["normal_velocity_after"]) / float(impact["normal_velocity_before"])


@pytest.mark.parametrize("mass", [0.005, 0.02826, 0.2])
@pytest.mark.parametrize("e", [0.5, 0.7, 0.9])
def test_restitution_on_a_hinged_hammer_at_the_default_step(tmp_path, mass, e):
    """One granule step per Pymunk step (the default): measured within 0.1 % for 5 g and 200 g."""
    summary, impacts = soft_run(
        tmp_path,
        replace={
            "mass = 0.02826": f"mass = {mass}",
            "restitution = 0.7": f"restitution = {e}",
            "granule_substeps = 2": "granule_substeps = 1",
        },
    )
    assert summary["status"] == "completed"
    assert impacts, "the hammer must strike the granule within 30 ms"
    assert restitution(impacts[0]) == pytest.approx(e, rel=0.005)
    assert abs(summary["energy"]["closure"]) < 0.005


@pytest.mark.parametrize(("mass", "substeps", "tolerance"), [(0.2, 10, 0.005), (0.005, 10, 0.005)])
def test_granule_substeps_where_they_pay(tmp_path, mass, substeps, tolerance):
    """During the substeps of one Pymunk step the kernel kicks the hammer by each granule
    step's loads, so a light hammer recoils within them. Measured e errors at e = 0.9 and 10
    substeps: 200 g +0.02 %, 5 g −0.22 % (docs/dev/validation.md); with the hammer at its velocity
    through the substeps the 5 g one was +0.96 %. Asserted: the restitution tolerance, 0.5 %."""
    _, impacts = soft_run(
        tmp_path,
        replace={
            "mass = 0.02826": f"mass = {mass}",
            "restitution = 0.7": "restitution = 0.9",
            "granule_substeps = 2": f"granule_substeps = {substeps}",
        },
    )
    assert restitution(impacts[0]) == pytest.approx(0.9, rel=tolerance)


def test_hertz_contacts(tmp_path):
    summary, impacts = soft_run(
        tmp_path,
        replace={'kind = "linear"\nduration = 1e-4': 'kind = "hertz"\nstiffness = 1e8'},
    )
    assert summary["time_step"]["contact_model"] == "hertz"
    assert restitution(impacts[0]) == pytest.approx(0.7, rel=0.005)
    assert abs(summary["energy"]["closure"]) < 0.005


# --- hard cases through the whole stack: each runs stably (no NaN, no lost granule) -------------


def _stable(summary, impacts, closure=0.01):
    """Completed, every impact value finite, and the ledger within ``closure`` (default 1 %: the
    runner's own warning threshold; these runs measured 0.02-0.42 %)."""
    assert summary["status"] == "completed", summary["reason"]
    assert abs(summary["energy"]["closure"]) < closure
    for impact in impacts:
        assert all(value not in ("nan", "inf") for value in impact.values())


def test_3000_rpm(tmp_path):
    """Tip speed 42 m/s: the step is still contact-governed; e within 0.5 %."""
    summary, impacts = soft_run(tmp_path, replace={"rpm = 600.0": "rpm = 3000.0"}, duration=0.01)
    _stable(summary, impacts)
    assert summary["time_step"]["governed_by"] == "contact"
    assert restitution(impacts[0]) == pytest.approx(0.7, rel=0.005)
    assert -float(impacts[0]["normal_velocity_before"]) > 30.0


def test_mass_ratio_1_to_20000(tmp_path):
    """A 0.1 g granule against a 2 kg hammer: the step follows the granule's mass. The ledger's
    resolution is the 45 J hammer's: the hinge joint's position correction moves its kinetic
    energy by parts per million, 1.8 % of the 3 mJ the rotor does here (residual measured
    1.2e-6 of the hammer's energy; the rigid engine at its own step, 2.2e-4 s: 2e-4, 26 %)."""
    summary, impacts = soft_run(
        tmp_path,
        replace={"mass = 0.02826": "mass = 2.0", "mass = 0.00016": "mass = 0.0001"},
        duration=0.03,
    )
    _stable(summary, impacts, closure=1.0)
    e = summary["energy"]
    scale = max(abs(e["drive_work"]), abs(e["kinetic"] - e["kinetic_initial"]))
    assert abs(e["closure"]) * scale < 2e-6 * e["kinetic"]
    assert restitution(impacts[0]) == pytest.approx(0.7, rel=0.005)


def test_restitution_0_05_with_the_overlap_end(tmp_path):
    """e = 0.05 is refused with end = 'force' (tests/cases/bad) and runs with 'overlap'; within
    1 % at t_c/50 (heavy damping's second-order error: tests/soft/test_hard_cases.py)."""
    summary, impacts = soft_run(
        tmp_path,
        replace={
            "restitution = 0.7": "restitution = 0.05",
            "duration = 1e-4": 'duration = 1e-4\nend = "overlap"',
        },
        duration=0.03,
    )
    _stable(summary, impacts)
    assert restitution(impacts[0]) == pytest.approx(0.05, rel=0.01)


def test_granule_at_the_hinge(tmp_path):
    """A granule resting on the leading face right at the hinge end of the hammer."""
    summary, impacts = soft_run(
        tmp_path,
        replace={"positions = [[0.0, 0.11]]": "positions = [[0.077, 0.0126]]"},
        duration=0.02,
    )
    _stable(summary, impacts)
    assert impacts


def test_hammer_swinging_to_its_stops(tmp_path):
    """A light hammer with stops at ±0.3 rad hit at the tip: it swings back onto its stop."""
    summary, impacts = soft_run(
        tmp_path,
        replace={
            'mount = "hinged"': 'mount = "hinged"\nswing_limit = 0.3',
            "mass = 0.02826": "mass = 0.003",
            "mass = 0.00016": "mass = 0.003",
            "positions = [[0.0, 0.11]]": "positions = [[0.0, 0.13]]",
        },
        duration=0.03,
    )
    _stable(summary, impacts)
    with (tmp_path / "run" / "hammers.csv").open() as f:
        alpha = [float(r["swing_angle"]) for r in csv.DictReader(f) if r["id"] == "0"]
    assert min(alpha) < -0.29  # it reached the stop ...
    assert min(alpha) >= -0.3 - 2e-3  # ... and stayed there (joint tolerance)


def hammer_restitution(
    model: str, e: float, end: str, mass: float, *, tip_speed: float | None = None,
    mount: str = "hinged",
) -> float:  # fmt: skip
    """e of the first impact of the soft single-granule case with hammer ``mass`` (kg),
    ``mount``ed, the pair's ``e``, contact ``model`` (Hertz by the case's duration) and
    ``end``, one granule step per machine step at the step plan's step: −v_n after / v_n
    before, relative to the hammer's material point (the impact log's). ``tip_speed``: the
    rotor turned so that the plate's tip (135 mm) moves at it, m/s (default: the case's
    600 rpm, 8.5 m/s)."""
    from perga.engine.simulation import Simulation
    from perga.model.compile import compile_case

    sets = [f"hammers.mass={mass}", f"contacts[0].restitution={e}", f'contact_model.end="{end}"',
            f'contact_model.kind="{model}"', "contact_model.granule_substeps=1",
            f'hammers.mount="{mount}"']  # fmt: skip
    if tip_speed is not None:
        sets.append(f"rotor.rpm={tip_speed / 0.135 * 60 / (2 * math.pi)!r}")
    sim = Simulation(compile_case(load_case(SOFT, overrides=sets)), track_energy=False)
    with sim.running():
        while not sim.impacts and sim.time < 0.2:
            sim.step()
    first = sim.impacts[0]
    return -first.normal_velocity_after / first.normal_velocity_before


@pytest.mark.parametrize("model", ["linear", "hertz"])
@pytest.mark.parametrize("e", [0.05, 0.1, 0.3])
@pytest.mark.parametrize("mass", [0.005, 0.2])
def test_heavy_damping_on_hinged_hammers_at_the_planned_step(model, e, mass):
    """Issue 16's must-show on 5 g and 200 g hinged hammers, linear and Hertz (by duration),
    at the default step plan (which gives heavily damped contacts more steps; e below e^-2
    with end = "overlap"): e within 0.5 % (measured at most −0.46 %, e = 0.05 on the 5 g
    hammer; −1.06 % at t_c/50 alone; the whole table: benchmarks/restitution_table.py)."""
    end = "overlap" if e < 0.2 else "force"
    assert hammer_restitution(model, e, end, mass) == pytest.approx(e, rel=5e-3)


@pytest.mark.slow
def test_the_turning_rotors_restitution_table() -> None:
    """``python benchmarks/restitution_table.py --turning`` as docs/dev/validation.md shows it
    (about 4 min): e from 0.6 up within 0.5 % in every cell (measured 0.11 % at most); below, the
    turning face's share, never more than 0.1 % above e and at most 3 % under it (measured
    −2.4 %, e = 0.05 at 40 m/s, Hertz)."""
    script = ROOT / "benchmarks" / "restitution_table.py"
    run = subprocess.run(
        [sys.executable, str(script), "--turning"], capture_output=True, text=True, check=True
    )
    rows = [
        [cell.strip() for cell in line.split("|")[1:-1]]
        for line in run.stdout.splitlines()
        if line.startswith(("| linear", "| hertz"))
    ]
    assert len(rows) == 36
    for _, _, e, *cells in rows:
        errors = [float(cell.rstrip("%")) / 100 for cell in cells]
        for error in errors:
            assert abs(error) < 0.005 if float(e) >= 0.6 else -0.03 < error < 0.001, (e, errors)
