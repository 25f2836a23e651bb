"""A sweep's plots speak the designer's units: rotor speed in rpm, hammer mass in g, fractions
in %, throughput in kg/h; a metric perga has no designer's unit for keeps its SI unit, named."""

from pathlib import Path

import pytest

from perga.studies import sweep_report
from perga.studies.user_units import axis_label, metric_label


def test_plots_are_drawn_in_the_designers_units(tmp_path: Path, monkeypatch) -> None:
    drawn = {}

    def keep(fig, path):
        drawn[path.name] = fig
        return True

    monkeypatch.setattr(sweep_report, "save", keep)
    rows = [
        {"rotor.rpm": rpm, "hammers.mass": mass, "throughput": 0.01 * rpm / 1000,
         "first_impact_restitution": 0.7, "status": "ok"}
        for rpm in (600.0, 1200.0) for mass in (0.025, 0.05)
    ]  # fmt: skip
    sweep_report.write_plots(rows, ["rotor.rpm", "hammers.mass"],
                             ["throughput", "first_impact_restitution"], tmp_path)  # fmt: skip
    ax = drawn["throughput__rotor_rpm.png"].axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("rotor speed [rpm]", "throughput [kg/h]")
    x, y = ax.lines[0].get_data()
    assert list(x) == [600.0, 600.0, 1200.0, 1200.0]
    assert list(y) == pytest.approx([21.6, 21.6, 43.2, 43.2], rel=1e-12)  # 0.006 kg/s = 21.6 kg/h
    ax = drawn["throughput__hammers_mass.png"].axes[0]
    assert ax.get_xlabel() == "hammer mass [g]" and sorted(ax.lines[0].get_data()[0]) == [
        25.0, 25.0, 50.0, 50.0
    ]  # fmt: skip
    mapped = drawn["map__throughput.png"].axes[0]
    assert (mapped.get_xlabel(), mapped.get_ylabel()) == ("rotor speed [rpm]", "hammer mass [g]")
    assert drawn["first_impact_restitution__rotor_rpm.png"].axes[0].get_ylabel() == (
        "first_impact_restitution [-]"
    )


def test_a_metric_without_a_designers_unit_keeps_its_si_unit() -> None:
    speed = "granule_speed_after_impact:1"
    assert metric_label(speed) == (f"{speed} [m/s]", 1.0)
    assert metric_label("damaged_fraction") == ("damaged [%]", 100.0)


def test_a_case_key_without_a_designers_unit_keeps_its_si_unit() -> None:
    assert axis_label("contacts.beebread-steel.restitution") == (
        "contacts.beebread-steel.restitution [-]", 1.0
    )  # fmt: skip
    assert axis_label("granules.placement.angle") == ("granules.placement.angle [rad]", 1.0)
    assert axis_label("hammers.mass") == ("hammer mass [g]", 1e3)
    assert axis_label("effects.unknown_key") == ("effects.unknown_key [SI]", 1.0)
