"""perga window: the four process metrics on hand-written run directories, the window and best
selection on a synthetic table, the options' checks, and one study end to end on Dask."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from perga.cli import main
from perga.stats.metrics import METRICS as REGISTRY
from perga.stats.metrics import MetricUnavailableError, evaluate
from perga.stats.tables import load_run
from perga.studies.pareto import pareto_front
from perga.studies.study_file import StudyError
from perga.studies.user_units import metric_label
from perga.studies.window import (
    METRICS,
    RELEASE,
    Point,
    aggregate,
    best_point,
    foundations,
    in_window,
    shortfall,
    trade_offs,
    trend,
    window_study,
)
from tests.case_text import case_text
from tests.figure_data import saved_figures

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

HELD_AT_START = [0, 1, 2, 3]  # ids held in comb cells at t = 0; 4 is a free granule
RELEASED = [0, 2, 9]  # 9: a granule fed later
OUTFLOW = [(0.001, 0.9), (0.002, 0.5), (0.0005, 1.0)]  # (mass kg, survival) of each one out
SURVIVAL_AT_END = [0.8, 0.6, 1.0, 0.4, 0.7]  # granules 0-4 in the chamber at the end, all free


def _write_run(
    directory: Path,
    *,
    held: list[int] | None = HELD_AT_START,
    releases: list[int] | None = RELEASED,
    damage: bool = True,
    outflow: list[tuple[float, float]] | None = OUTFLOW,
    simulated_time: float = 0.5,
    drive_work: float | None = 7.0,
) -> Path:
    """A run directory as perga run writes it, with only what the process metrics read."""
    directory.mkdir(parents=True)
    extra = '[damage]\naction = "mark"\n' if damage else ""
    breakage = "breakage = { f_mat = 0.1, w_min = 30.0 }" if damage else ""
    (directory / "case.toml").write_text(
        CASE_TOML.format(detachment=f"detachment_force = 0.02\n{breakage}") + extra
    )
    summary: dict = {"case": "", "status": "completed", "simulated_time": simulated_time}
    if drive_work is not None:
        summary["energy"] = {"drive_work": drive_work, "closure": 0.0}
    (directory / "summary.json").write_text(json.dumps(summary))
    head = "time,id,x,y,vx,vy,angular_velocity,speed,radius,mass" + (",held" if held else "")
    head += ",survival,broken,damaging_impacts" if damage else ""
    rows = [
        f"{t},{i},0,0,0,0,0,0,0.0025,1e-4"
        + (f",{int(t == 0.0 and i in held)}" if held else "")
        + (f",{SURVIVAL_AT_END[i] if t > 0 else 1.0},0,0" if damage else "")
        for t in (0.0, 0.1)
        for i in range(5)
    ]
    (directory / "granules.csv").write_text("\n".join([head, *rows]) + "\n")
    if releases is not None:
        body = [f"0.01,{g},600.0" for g in releases]
        (directory / "releases.csv").write_text("\n".join(["time,granule,force", *body]) + "\n")
    if outflow is not None:
        head = "time,granule,radius,mass,speed,impacts,survival,broken,residence_time"
        body = [f"0.1,{i},0.0025,{m},3.0,1,{s},0,0.1" for i, (m, s) in enumerate(outflow)]
        (directory / "outflow.csv").write_text("\n".join([head, *body]) + "\n")
    return directory


def test_the_metrics_of_a_run_by_hand(tmp_path: Path) -> None:
    """released: 0 and 2 of the 4 held at t = 0 (9 came later) = 0.5; damage of the granules
    out of the comb 1 − (0.9 + 0.5 + 1.0 + 0.8 + 0.6 + 1.0 + 0.4 + 0.7)/8 = 0.2625 (three gone,
    five free in the chamber); throughput 0.0035 kg / 0.5 s; energy 7 J / 0.0035 kg."""
    run = load_run(_write_run(tmp_path / "run"))
    assert evaluate(run, "released_fraction") == 0.5
    assert evaluate(run, "damaged_fraction") == pytest.approx(0.2625, abs=1e-15)
    assert evaluate(run, "throughput") == pytest.approx(0.0035 / 0.5, rel=1e-14)
    assert evaluate(run, "energy_per_kg") == pytest.approx(7.0 / 0.0035, rel=1e-14)
    units = {m: REGISTRY[m].unit for m in METRICS}
    assert units == {
        "released_fraction": "-",
        "damaged_fraction": "-",
        "throughput": "kg/s",
        "energy_per_kg": "J/kg",
    }


def test_nothing_released_and_no_outflow(tmp_path: Path) -> None:
    run = load_run(_write_run(tmp_path / "run", releases=[], outflow=[]))
    assert evaluate(run, "released_fraction") == 0.0
    assert evaluate(run, "throughput") == 0.0
    assert evaluate(run, "damaged_fraction") == pytest.approx(1 - 3.5 / 5, abs=1e-15)
    with pytest.raises(MetricUnavailableError, match="no product left"):
        evaluate(run, "energy_per_kg")


@pytest.mark.parametrize(
    ("options", "metric", "reason"),
    [
        ({"held": None}, "released_fraction", "no granule was held"),
        ({"held": [7]}, "released_fraction", "no granule was held in a comb cell at t = 0"),
        ({"releases": None}, "released_fraction", "did not record granules and releases"),
        ({"damage": False}, "damaged_fraction", r"no \[damage\]"),
        ({"outflow": None}, "damaged_fraction", "outflow"),
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


def test_runs_whose_ledger_is_off_count_as_failed_with_their_reason() -> None:
    """A run the runner judged "completed, ledger off" is left out of its point's means and
    counted as failed; its reason is among the point's notes."""
    reason = "the energy ledger closes to -1.20 %, beyond solver.ledger_tolerance = 0.01"
    rows = [
        {"a": 1.0, "b": 2.0, "status": "ok", RELEASE: 0.5, "ledger_closure": 0.002},
        {"a": 1.0, "b": 2.0, "status": "completed, ledger off", "reason": reason,
         RELEASE: 0.9, "ledger_closure": -0.012},
    ]  # fmt: skip
    (point,) = aggregate(rows, ("a", "b"), ([1.0], [2.0]))
    assert (point.runs, point.failed, point.mean[RELEASE]) == (2, 1, 0.5)
    assert point.notes == [reason]


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
def test_window_end_to_end_on_dask(tmp_path: Path, monkeypatch) -> None:
    """The bundled separator case over 600 and 1800 rpm × 0.05 and 0.075 kg hammers, three
    replicates each, on two Dask workers: the files, and the trends physics demands. At each
    mass every run at 1800 rpm has a higher mean breakage probability per impact than every run
    at 600 rpm (measured 0.04-0.10 against 0.14-0.18: the impact's specific energy grows with
    the tip speed squared). The expected damage of the granules out of the comb and the released
    fraction do not fall by more than twice the combined sd √(sd₁² + sd₂²): three 0.3 s
    replicates cannot show damage rising, since at 600 rpm a granule out of the comb may stay in
    the chamber and be struck again and again (a replicate at 50 g: no product, damage 0.55,
    the point 0.31 ± 0.21 against 0.27 ± 0.05 at 1800 rpm); the full map shows the rise
    (docs/explanation/operating-window.md). The comb's release needs a peak force that grows
    with speed."""
    out = tmp_path / "window"
    saved = saved_figures(monkeypatch)
    code = main(
        ["window", str(CASE), "--set", "rotor.rpm=600:1800:2", "--set", "hammers.mass=0.05:0.075:2",
         "--replicates", "3", "--set", "solver.duration=0.3", "--workers", "2", "-o", str(out),
         "--quiet"]
    )  # fmt: skip
    assert code == 0
    for name in ("window.parquet", "window.csv", "window.png", "report.md", "results.parquet"):
        assert (out / name).is_file(), name
    table = pq.read_table(out / "window.parquet").to_pydict()
    for panel, metric in zip(saved["window.png"].axes, METRICS, strict=False):  # the maps' data
        mesh = next(c for c in panel.collections if hasattr(c, "get_array"))
        means = np.array(table[f"{metric}_mean"]) * metric_label(metric)[1]  # the user's units
        assert np.array_equal(
            np.sort(mesh.get_array().compressed()), np.sort(means[~np.isnan(means)])
        )
        assert panel.get_xlabel() == "rotor speed [rpm]" and panel.get_ylabel() == "hammer mass [g]"
    rings = [line.get_xydata()[0] for line in saved["trade-offs.png"].axes[0].get_lines()]
    front = [(t * 3600, d * 100) for t, d in zip(table["throughput_mean"],
             table["damaged_fraction_mean"], strict=True)]  # fmt: skip
    values = np.array([[table[f"{m}_mean"][i] for m in ("throughput", "damaged_fraction",
                       "energy_per_kg")] for i in range(4)])  # fmt: skip
    expected = pareto_front(values, ["max", "min", "min"])
    assert sorted(map(tuple, np.round(rings, 9))) == sorted(
        tuple(np.round(front[i], 9)) for i in expected
    )
    points = sorted(zip(table["hammers.mass"], table["rotor.rpm"], range(4), strict=True))
    assert [(m, s) for m, s, _ in points] == [
        (0.05, 600.0), (0.05, 1800.0), (0.075, 600.0), (0.075, 1800.0)
    ]  # fmt: skip
    assert table["runs"] == [3] * 4 and table["failed"] == [0] * 4
    for (_, _, slow), (_, _, fast) in (points[0:2], points[2:4]):

        def mean_sd(metric: str, i: int) -> tuple[float, float]:
            return table[f"{metric}_mean"][i], table[f"{metric}_sd"][i]

        for metric in ("damaged_fraction", "released_fraction"):
            (m0, s0), (m1, s1) = mean_sd(metric, slow), mean_sd(metric, fast)
            assert m1 >= m0 - 2 * math.hypot(s0, s1), (metric, m0, s0, m1, s1)
    results = pq.read_table(out / "results.parquet").to_pydict()
    assert len(results["key"]) == 12 and len(set(results["seed"])) == 3
    breakage: dict[tuple[float, float], list[float]] = {}
    for rpm, mass, run in zip(
        results["rotor.rpm"], results["hammers.mass"], results["directory"], strict=True
    ):
        table = np.genfromtxt(Path(run) / "impacts.csv", delimiter=",", names=True)
        breakage.setdefault((mass, rpm), []).append(float(np.mean(table["breakage_probability"])))
    for mass in (0.05, 0.075):
        assert min(breakage[(mass, 1800.0)]) > max(breakage[(mass, 600.0)]), breakage
    report = (out / "report.md").read_text()
    assert "## Best setting" in report and "## Trends along rotor.rpm" in report
    assert "## Trade-offs" in report and any(f" rpm, {g} g |" in report for g in (50, 75))


def _traded(x: float, throughput: float, damage: float, energy: float) -> Point:
    mean = {"released_fraction": 1.0, "damaged_fraction": damage, "throughput": throughput,
            "energy_per_kg": energy}  # fmt: skip
    return Point(x, 0.0, 2, 0, mean, dict.fromkeys(mean, 0.0), dict.fromkeys(mean, 2))


def test_trade_offs_are_the_settings_no_other_beats_on_all_three() -> None:
    """Throughput up, damage and energy per kg down: (0.2, 0.01, 300) is beaten by
    (0.2, 0.01, 250) and (0.1, 0.03, 400) by both others; a point without a throughput is never
    on the front."""
    points = [_traded(1, 0.2, 0.01, 300), _traded(2, 0.3, 0.02, 300),
              _traded(3, 0.2, 0.01, 250), _traded(4, 0.1, 0.03, 400),
              _traded(5, math.nan, 0.0, 1.0)]  # fmt: skip
    assert [p.x for p in trade_offs(points)] == [2, 3]


def test_the_report_says_what_the_map_rests_on(tmp_path: Path) -> None:
    """The bundled case: soft contacts of 0.1 ms and its step, the energy law that makes the
    release independent of both; with rigid contacts the step; a case with the force law only
    says its release depends on the numerics."""
    sets = ["rotor.rpm=600:1800:2", "hammers.mass=0.05:0.075:2"]
    soft = "\n".join(foundations(window_study(CASE, sets)))
    assert "soft linear contacts, contact duration 0.1 ms" in soft and "granule step" in soft
    assert "detachment_energy = 0.06 J" in soft and "whatever the contact's stiffness" in soft
    assert "none calibrated" in soft
    with pytest.raises(StudyError, match="a study's values are numbers, strings or booleans"):
        window_study(CASE, [*sets, 'contact_model={kind="rigid"}'])
    rigid_case = tmp_path / "rigid.toml"
    text = case_text(CASE).replace("../geometry", str(ROOT / "geometry"))
    start = text.index("[contact_model]")
    rigid_case.write_text(text[:start] + '[contact_model]\nkind = "rigid"\n\n' +
                          text[text.index("[solver]"):])  # fmt: skip
    rigid = foundations(window_study(rigid_case, sets))
    assert rigid[0].startswith("- contacts: rigid impulses (Pymunk), step ")
    forced = tmp_path / "forced.toml"
    forced.write_text(text.replace("detachment_energy = 0.06\n", ""))
    lines = foundations(window_study(forced, sets), calibrated=True)
    assert "the release depends on the numerics" in lines[1] and len(lines) == 2
