"""--set KEY=VALUE overrides: applied to the file's data and checked exactly like the file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from perga.case import CaseError, load_case
from perga.case.overrides import OverrideError, apply_overrides, parse_value
from perga.cli import main

ROOT = Path(__file__).resolve().parents[2]
SEPARATOR = ROOT / "cases" / "separator.toml"
REBOUND = ROOT / "cases" / "rebound-test.toml"


def test_values_are_toml_or_strings() -> None:
    assert parse_value("2400") == 2400
    assert parse_value("0.65") == 0.65
    assert parse_value("[0.1, 0.2]") == [0.1, 0.2]
    assert parse_value("true") is True
    assert parse_value('"vertical"') == parse_value("vertical") == "vertical"


def test_keys_of_tables_lists_and_contact_pairs() -> None:
    case = load_case(
        SEPARATOR,
        overrides=[
            "rotor.rpm=2400",
            "hammers.mass=0.05",
            "materials.beebread.density=1300",
            "contacts.granule-hammer.restitution=0.65",  # roles
            "contacts.beebread-beebread.friction=0.45",  # materials, either order
            "contacts[0].friction=0.3",  # index
            "effects.air_drag.drag_coefficient=0.9",  # a table created
        ],
    )
    assert case.rotor.rpm == 2400
    assert case.hammers.mass == 0.05
    assert case.materials["beebread"].density == 1300
    assert case.granule_hammer_contact.restitution == 0.65
    assert case.granule_hammer_contact.friction == 0.3
    assert case.contact("beebread", "beebread").friction == 0.45
    assert case.effects.air_drag is not None and case.effects.air_drag.drag_coefficient == 0.9
    assert case.overrides[0] == "rotor.rpm=2400"


def test_the_file_is_not_changed_and_data_is_copied() -> None:
    data = {"rotor": {"rpm": 600.0}}
    out = apply_overrides(data, [("rotor.rpm", 1200.0)])
    assert data == {"rotor": {"rpm": 600.0}} and out == {"rotor": {"rpm": 1200.0}}


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("rotor.rpm=0", "rotor.rpm: Input should be greater than or equal to 0.00001 (got 0)"),
        ("rotor.rpm=20001", "rotor.rpm: Input should be less than or equal to 20000"),
        ("rotor.rpmm=3", "rotor.rpmm: unknown key; did you mean 'rpm'?"),
        ("contacts.granule-wall.friction=1", "no [[contacts]] entry for the pair beebread-wall"),
        ("contacts[7].friction=0.1", "index 7 out of range (the list has 2)"),
        ("rotor.rpm[0]=1", "[0] indexes something that is not a list"),
        ("nokey", "expected KEY=VALUE"),
        ("contacts.granule-hammer.friction=2.5", "contacts[0].friction: Input should be less"),
    ],
)
def test_bad_overrides_name_the_file_and_the_key(override: str, message: str) -> None:
    with pytest.raises(CaseError) as exc:
        load_case(SEPARATOR, overrides=[override])
    text = str(exc.value)
    assert str(SEPARATOR) in text and message in text, text


def test_limits_both_sides_like_the_file() -> None:
    """The schema's limits hold for overrides on both sides: friction 2 is accepted, 2.0001
    refused; gravity 100 m/s² accepted, 100.1 refused."""
    assert load_case(SEPARATOR, overrides=["contacts[0].friction=2"]).contacts[0].friction == 2
    with pytest.raises(CaseError):
        load_case(SEPARATOR, overrides=["contacts[0].friction=2.0001"])
    assert load_case(SEPARATOR, overrides=["gravity=100"]).gravity == 100
    with pytest.raises(CaseError):
        load_case(SEPARATOR, overrides=["gravity=100.1"])


def test_index_on_a_missing_list_is_refused() -> None:
    with pytest.raises(OverrideError, match="not in the case"):
        apply_overrides({}, [("contacts[0].friction", 0.1)])


def test_a_run_records_its_overrides(tmp_path: Path, capsys) -> None:
    """perga run --set: the run's case.toml is the file with the overrides applied (and lists
    them), summary.json lists them, and the run used them; a bad override exits 2."""
    out = tmp_path / "run"
    code = main(["run", str(REBOUND), "-o", str(out), "--quiet",
                 "--set", "contacts.granule-hammer.restitution=0.55",
                 "--set", "granules.placement.angle=0.0"])  # fmt: skip
    assert code == 0
    text = (out / "case.toml").read_text()
    assert "# --set contacts.granule-hammer.restitution=0.55" in text
    again = load_case(out / "case.toml")
    assert again.granule_hammer_contact.restitution == 0.55
    summary = json.loads((out / "summary.json").read_text())
    assert summary["overrides"] == [
        "contacts.granule-hammer.restitution=0.55",
        "granules.placement.angle=0.0",
    ]
    from perga.stats import load_run
    from perga.stats.metrics import evaluate

    assert evaluate(load_run(out), "first_impact_restitution") == pytest.approx(0.55, abs=1e-12)
    assert main(["run", str(REBOUND), "-o", str(tmp_path / "bad"), "--set", "rotor.rpm=-1"]) == 2
    assert "rotor.rpm: Input should be greater than or equal to 0.00001" in capsys.readouterr().err


def test_a_bad_value_is_blamed_on_the_set_that_gave_it(tmp_path) -> None:
    """A problem the file alone does not have names the --set that made it (by its key, or
    every --set when the key is not one of theirs); the file's own problems name the file."""
    with pytest.raises(CaseError) as exc:
        load_case(SEPARATOR, overrides=["rotor.speed=900", "solver.duration=0.1"])
    assert exc.value.problems == [
        f"{SEPARATOR} with --set rotor.speed=900: rotor.speed: unknown key; did you mean 'rpm' "
        "or 'omega'?"
    ]
    with pytest.raises(CaseError) as exc:
        load_case(SEPARATOR, overrides=["contacts.granule-hammer.friction=2.5"])
    assert exc.value.problems[0].startswith(
        f"{SEPARATOR} with --set contacts.granule-hammer.friction=2.5: contacts[0].friction: "
    )
    bad = tmp_path / "bad.toml"
    bad.write_text(SEPARATOR.read_text().replace("rpm = ", "rmp = ", 1))
    with pytest.raises(CaseError) as exc:
        load_case(bad, overrides=["rotor.radius=0.2"])
    assert exc.value.problems == [f"{bad}: rotor.rmp: unknown key; did you mean 'rpm'?"]
