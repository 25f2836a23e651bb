"""perga window: the four process metrics on hand-written run directories, the window and best
selection on a synthetic table, the options' checks, and one study end to end on Dask."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from perga.cli import main
from perga.stats.metrics import METRICS as REGISTRY
from perga.stats.metrics import MetricUnavailableError, evaluate
from perga.stats.tables import load_run
from perga.studies.window import (
    METRICS,
    Point,
    best_point,
    in_window,
    shortfall,
    trend,
)

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "bee-bread-separator.toml"

CASE_TOML = """
[rotor]
plane = "horizontal"
omega = 1e-4
radius = 0.15

[hammers]
count = 1
mass = 0.1
hinge_radius = 0.0
mount = "welded"
shape = {{ kind = "plate", length = 0.1, width = 0.02 }}

[granules]
count = 1
radius = 0.0025
mass = 0.00016
material = "beebread"
placement = {{ kind = "shot", speed = 5.0, angle = 0.5, spin = 0.0, gap = 0.001 }}

[chamber]
radius = 0.2

[materials.beebread]
density = 1400.0
{detachment}

[materials.steel]
density = 7850.0

[[contacts]]
pair = ["beebread", "steel"]
restitution = 0.7
friction = 0.3

[solver]
dt = 2e-6
duration = 0.003
"""

POPULATION = {
    "fed": 8,
    "released": 6,
    "departed": 3,
    "broken": 1,
    "removed_broken": 0,
    "present": 5,
}
IMPACTS = [  # time, granule, survival (cumulative: a granule's last row counts)
    (0.01, 0, 0.9),
    (0.02, 1, 0.5),
    (0.03, 0, 0.6),
    (0.04, 2, 1.0),
    (0.05, 1, 0.25),
]
OUTFLOW_MASS = [0.001, 0.002, 0.0005]  # kg


def _write_run(
    directory: Path,
    *,
    held: bool = True,
    population: dict | None = POPULATION,
    impacts: list | None = IMPACTS,
    survival: bool = True,
    outflow: list[float] | None = OUTFLOW_MASS,
    simulated_time: float = 0.5,
    drive_work: float | None = 7.0,
) -> Path:
    """A run directory as perga run writes it, with only what the process metrics read."""
    directory.mkdir(parents=True)
    detachment = "detachment_force = 0.02" if held else ""
    (directory / "case.toml").write_text(CASE_TOML.format(detachment=detachment))
    summary: dict = {"case": "", "status": "completed", "simulated_time": simulated_time}
    if population is not None:
        summary["population"] = population
    if drive_work is not None:
        summary["energy"] = {"drive_work": drive_work, "closure": 0.0}
    (directory / "summary.json").write_text(json.dumps(summary))
    if impacts is not None:
        head = "time,granule,hammer,normal_velocity_before" + (",survival" if survival else "")
        body = [f"{t},{g},0,-1.0" + (f",{s}" if survival else "") for t, g, s in impacts]
        (directory / "impacts.csv").write_text("\n".join([head, *body]) + "\n")
    if outflow is not None:
        head = "time,granule,radius,mass,speed,impacts,survival,broken,residence_time"
        body = [f"0.1,{i},0.0025,{m},3.0,1,1.0,0,0.1" for i, m in enumerate(outflow)]
        (directory / "outflow.csv").write_text("\n".join([head, *body]) + "\n")
    (directory / "releases.csv").write_text("time,granule,force\n0.01,0,0.05\n")
    return directory


def test_the_metrics_of_a_run_by_hand(tmp_path: Path) -> None:
    """released 6/8; damage (1−0.6 + 1−0.25 + 1−1.0)/8 (granules 3-7 had no impact: survival 1);
    throughput 0.0035 kg / 0.5 s; energy 7 J / 0.0035 kg."""
    run = load_run(_write_run(tmp_path / "run"))
    assert evaluate(run, "released_fraction") == 0.75
    assert evaluate(run, "damaged_fraction") == pytest.approx((0.4 + 0.75 + 0.0) / 8, abs=1e-15)
    assert evaluate(run, "throughput") == pytest.approx(0.0035 / 0.5, rel=1e-14)
    assert evaluate(run, "energy_per_kg") == pytest.approx(7.0 / 0.0035, rel=1e-14)
    units = {m: REGISTRY[m].unit for m in METRICS}
    assert units == {
        "released_fraction": "-",
        "damaged_fraction": "-",
        "throughput": "kg/s",
        "energy_per_kg": "J/kg",
    }


def test_no_impact_no_damage_and_no_outflow_no_throughput(tmp_path: Path) -> None:
    run = load_run(_write_run(tmp_path / "run", impacts=[], outflow=[]))
    assert evaluate(run, "damaged_fraction") == 0.0
    assert evaluate(run, "throughput") == 0.0
    with pytest.raises(MetricUnavailableError, match="no product left"):
        evaluate(run, "energy_per_kg")


@pytest.mark.parametrize(
    ("options", "metric", "reason"),
    [
        ({"held": False}, "released_fraction", "no detachment_force"),
        ({"population": None}, "released_fraction", "population"),
        ({"population": {**POPULATION, "fed": 0}}, "released_fraction", "no granule was fed"),
        ({"population": None}, "damaged_fraction", "population"),
        ({"survival": False}, "damaged_fraction", r"no \[damage\]"),
        ({"impacts": None}, "damaged_fraction", "did not record impacts"),
        ({"outflow": None}, "throughput", "outflow"),
        ({"simulated_time": 0.0}, "throughput", "simulated no time"),
        ({"outflow": None}, "energy_per_kg", "outflow"),
        ({"drive_work": None}, "energy_per_kg", "did not track energy"),
    ],
)
def test_unavailable_metrics_say_why(
    tmp_path: Path, options: dict, metric: str, reason: str
) -> None:
    run = load_run(_write_run(tmp_path / "run", **options))
    with pytest.raises(MetricUnavailableError, match=reason):
        evaluate(run, metric)


def _point(x: float, y: float, release: float, damage: float, through: float, energy: float,
           sd: float = 0.0) -> Point:  # fmt: skip
    means = dict(zip(METRICS, (release, damage, through, energy), strict=True))
    return Point(x, y, 2, 0, means, dict.fromkeys(METRICS, sd), dict.fromkeys(METRICS, 2))


def test_window_edges_are_inclusive_on_both_limits() -> None:
    """release ≥ 0.9 and damage ≤ 0.05: exactly on a limit is inside, a hair past is not."""
    assert in_window(_point(0, 0, 0.9, 0.05, 1, 1), 0.9, 0.05)
    assert not in_window(_point(0, 0, 0.9 - 1e-9, 0.05, 1, 1), 0.9, 0.05)
    assert not in_window(_point(0, 0, 0.9, 0.05 + 1e-9, 1, 1), 0.9, 0.05)
    assert in_window(_point(0, 0, 1.0, 0.0, 1, 1), 0.9, 0.05)
    assert not in_window(_point(0, 0, math.nan, 0.0, 1, 1), 0.9, 0.05)
    # ±1 sd: 0.95 ± 0.1 leaves the window when pessimistic; 0.85 ± 0.1 enters it when optimistic
    assert not in_window(_point(0, 0, 0.95, 0.0, 1, 1, sd=0.1), 0.9, 0.05, shift=1.0)
    assert in_window(_point(0, 0, 0.85, 0.0, 1, 1, sd=0.01), 0.9, 0.05, shift=-10.0)
    assert not in_window(_point(0, 0, 0.85, 0.0, 1, 1, sd=0.01), 0.9, 0.05, shift=-1.0)


def test_best_is_the_highest_throughput_inside_ties_by_energy() -> None:
    points = [
        _point(600, 0.03, 0.80, 0.01, 9.0, 1.0),  # release below target: out
        _point(900, 0.03, 0.95, 0.10, 9.0, 1.0),  # damage above limit: out
        _point(1200, 0.03, 0.92, 0.04, 5.0, 300.0),  # in: ties with the next on throughput
        _point(1500, 0.03, 0.99, 0.02, 5.0, 200.0),  # in, lower energy: best
        _point(600, 0.06, 0.91, 0.00, 4.0, 100.0),  # in, lower throughput
    ]
    best = best_point(points, 0.9, 0.05)
    assert best.inside and (best.point.x, best.point.y) == (1500, 0.03)
    # a stricter damage limit leaves only the last one
    best = best_point(points, 0.9, 0.01)
    assert best.inside and (best.point.x, best.point.y) == (600, 0.06)


def test_no_setting_meets_both_names_the_nearest() -> None:
    points = [
        _point(600, 0.03, 0.50, 0.00, 1.0, 1.0),  # 0.4 short
        _point(900, 0.03, 0.85, 0.06, 1.0, 1.0),  # 0.05 + 0.01 = 0.06 short: nearest
        _point(1200, 0.03, 0.95, 0.20, 1.0, 1.0),  # 0.15 over
        _point(1500, 0.03, math.nan, 0.0, 1.0, 1.0),  # no release: never named
    ]
    assert shortfall(points[1], 0.9, 0.05) == pytest.approx(0.06, abs=1e-15)
    assert math.isinf(shortfall(points[3], 0.9, 0.05))
    best = best_point(points, 0.9, 0.05)
    assert not best.inside and best.point.x == 900
    assert best_point([points[3]], 0.9, 0.05).point is None


def test_trend_counts_pairs_and_spread() -> None:
    """Speeds 1, 2, 3 with means 0.1, 0.3, 0.2 (sd 0.05): pairs (1,2) +0.2 clear, (1,3) +0.1
    clear (> 0.0707), (2,3) −0.1 clear; Spearman ρ = 0.5."""
    t = trend([3.0, 1.0, 2.0], [0.2, 0.1, 0.3], [0.05] * 3, "damaged_fraction", 0.03)
    assert (t.pairs, t.rising, t.falling, t.equal) == (3, 2, 1, 0)
    assert (t.rising_clear, t.falling_clear) == (2, 1)
    assert t.rho == pytest.approx(0.5)
    t = trend([1.0, 2.0], [0.2, 0.25], [0.05, 0.05], "damaged_fraction", 0.03)
    assert (t.rising, t.rising_clear) == (1, 0)  # 0.05 rise within the spread 0.0707
    t = trend([1.0, 2.0], [1.0, 1.0], [0.0, 0.0], "released_fraction", 0.03)
    assert (t.equal, t.falling) == (1, 0) and math.isnan(t.rho)


@pytest.mark.parametrize(
    ("options", "named"),
    [
        (["--set", "rotor.rpmx=600:1500:2"], "rotor.rpmx"),
        (["--set", "rotor.rpm=600:1500:1"], "--set rotor.rpm=600:1500:1"),
        (["--set", "hammers.mass=0.06:0.03:2"], "--set hammers.mass=0.06:0.03:2"),
        (["--release-target", "1.01"], "--release-target"),
        (["--release-target", "-0.01"], "--release-target"),
        (["--damage-limit", "1.5"], "--damage-limit"),
        (["--damage-limit=-1e-6"], "--damage-limit"),
        (["--replicates", "0"], "--replicates"),
        (["--set", "solver.seed=3"], "--set solver.seed=3"),
        (["--set", "solver.duration=0.1:0.2:2"], "exactly two keys"),
    ],
)
def test_bad_options_exit_2_naming_the_option(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], options: list[str], named: str
) -> None:
    axes = {"rotor.rpm": "600:1500:2", "hammers.mass": "0.03:0.06:2"}
    for text in options:
        key = text.partition("=")[0]
        axes.pop(key, None)
    argv = ["window", str(CASE), "-o", str(tmp_path / "out")]
    for key, values in axes.items():
        argv += ["--set", f"{key}={values}"]
    assert main([*argv, *options]) == 2
    err = capsys.readouterr().err
    assert named in err, err
    assert not (tmp_path / "out").exists()


def test_limits_on_the_edges_are_accepted(tmp_path: Path) -> None:
    """0 and 1 are allowed targets: the options are checked, no run starts."""
    from perga.studies.window import window_study

    sets = ["rotor.rpm=600:1500:2", "hammers.mass=0.03:0.06:2", "solver.duration=0.01"]
    window = window_study(CASE, sets, release_target=1.0, damage_limit=0.0)
    assert window.axes == ("rotor.rpm", "hammers.mass") and window.speed_axis == "rotor.rpm"
    assert window.grid() == ([600.0, 1500.0], [0.03, 0.06])
    window = window_study(CASE, sets, release_target=0.0, damage_limit=1.0)
    assert (window.release_target, window.damage_limit) == (0.0, 1.0)


@pytest.mark.slow
def test_window_end_to_end_on_dask(tmp_path: Path) -> None:
    """The bundled separator case over 2 speeds × 2 hammer masses, 2 replicates, two workers."""
    out = tmp_path / "window"
    code = main(
        ["window", str(CASE), "--set", "rotor.rpm=600:1500:2", "--set", "hammers.mass=0.03:0.06:2",
         "--replicates", "2", "--set", "solver.duration=0.15", "--workers", "2", "-o", str(out),
         "--quiet"]
    )  # fmt: skip
    assert code == 0
    for name in ("window.parquet", "window.csv", "window.png", "report.md", "results.parquet"):
        assert (out / name).is_file(), name
    table = pq.read_table(out / "window.parquet").to_pydict()
    assert sorted(zip(table["rotor.rpm"], table["hammers.mass"], strict=True)) == [
        (600.0, 0.03), (600.0, 0.06), (1500.0, 0.03), (1500.0, 0.06)
    ]  # fmt: skip
    for m in METRICS:
        assert len(table[f"{m}_mean"]) == 4 and len(table[f"{m}_sd"]) == 4
    assert table["runs"] == [2] * 4 and table["failed"] == [0] * 4
    for value in table["released_fraction_mean"] + table["damaged_fraction_mean"]:
        assert 0.0 <= value <= 1.0
    results = pq.read_table(out / "results.parquet").to_pydict()
    assert len(results["key"]) == 8 and len(set(results["seed"])) == 2
    report = (out / "report.md").read_text()
    assert "## Best setting" in report and "## Trends along rotor.rpm" in report
