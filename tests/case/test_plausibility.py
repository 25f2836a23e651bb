"""Material values outside the range of real materials are warned about, not refused, naming
the unit they were probably typed in; values at the limits pass quietly; the bundled cases warn
of nothing."""

from pathlib import Path

import pytest

from perga.case import load_case
from perga.case.plausibility import DENSITY, MODULUS, implausible
from perga.cli import main

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "single-granule.toml"
SOFT = ROOT / "cases" / "soft-separator.toml"


def _warnings(*overrides: str, case: Path = CASE) -> list[str]:
    return implausible(load_case(case, overrides=overrides))


@pytest.mark.parametrize("density", [DENSITY[0], DENSITY[1]])
def test_densities_at_the_limits_pass(density: float) -> None:
    assert _warnings(f"materials.beebread.density={density}") == []


def test_a_density_in_g_per_cm3_is_named() -> None:
    (line,) = _warnings("materials.beebread.density=1.4")
    assert line.startswith("materials.beebread.density = 1.4 kg/m³ is outside")
    assert line.endswith("typed in g/cm³? 1.4 g/cm³ is 1400 kg/m³")
    (line,) = _warnings(f"materials.beebread.density={DENSITY[0] * 0.99}")
    assert "typed in g/cm³" not in line  # 99 g/cm³ is no material either
    (line,) = _warnings(f"materials.steel.density={DENSITY[1] * 1.01}")
    assert line.startswith("materials.steel.density = 25250 kg/m³ is outside")


def test_a_modulus_in_mpa_or_gpa_is_named() -> None:
    key = "materials.steel.youngs_modulus"
    assert _warnings(f"{key}={MODULUS[0]}", case=SOFT) == []
    assert _warnings(f"{key}={MODULUS[1]}", case=SOFT) == []
    (line,) = _warnings(f"{key}=210000", case=SOFT)
    assert line.endswith("typed in MPa? 210000 MPa is 2.1e+11 Pa")
    (line,) = _warnings(f"{key}=1100", case=SOFT)
    assert line.endswith("typed in GPa? 1100 GPa is 1.1e+12 Pa")
    (line,) = _warnings(f"{key}={MODULUS[1] * 1.01}", case=SOFT)
    assert "is outside the moduli" in line and "typed in" not in line


def test_the_bundled_cases_warn_of_nothing() -> None:
    for case in sorted((ROOT / "cases").glob("*.toml")):
        assert implausible(load_case(case)) == [], case.name


def test_validate_warns_and_still_passes(tmp_path: Path, capsys) -> None:
    case = tmp_path / "grams.toml"
    case.write_text(CASE.read_text().replace("density = 1400.0", "density = 1.4", 1))
    assert main(["validate", str(case)]) == 0
    out, err = capsys.readouterr()
    assert out == f"ok: {case}\n"
    assert err == (
        f"warning: {case}: materials.beebread.density = 1.4 kg/m³ is outside the densities of "
        "real granules and machine parts (100-25000 kg/m³); typed in g/cm³? 1.4 g/cm³ is 1400 "
        "kg/m³\n"
    )
    run = ["run", str(case), "--quiet", "-o", str(tmp_path / "run"), "--set",
           "solver.duration=0.001"]  # fmt: skip
    assert main(run) == 0
    assert "typed in g/cm³? 1.4 g/cm³ is 1400 kg/m³" in capsys.readouterr().err
