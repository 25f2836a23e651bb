"""Materials as users know them (issue 16, item 1): Hertz stiffness of each pair from the
materials' Young's moduli and Poisson's ratios, E* and R* as a hand calculation gives them; R*
from each contact's own radii, a wall flat whatever its material (issue 17, item 1; issue 19,
item 4); and the refusals around it, each on both sides of its limit."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import pytest

from perga.case import CaseError
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case, validated

E_BB, NU_BB = 5.0e6, 0.35  # Pa, -: a soft granule material (issue 19's)
E_STEEL, NU_STEEL = 2.1e11, 0.30
CHAMBER = 0.1  # m

CASE = f"""
[rotor]
plane = "horizontal"
rpm = 60.0
radius = 0.02

[hammers]
count = 1
mass = 0.005
hinge_radius = 0.015
material = "steel"
shape = {{ kind = "plate", length = 0.02, width = 0.005, hinge_offset = 0.002 }}

[granules]
count = 1
radius = 0.003
thickness = 0.01
material = "beebread"
placement = {{ kind = "explicit", positions = [[0.0, 0.09]] }}

[chamber]
radius = {CHAMBER}
material = "beebread"

[materials.beebread]
density = 1300.0
youngs_modulus = {E_BB}
poisson_ratio = {NU_BB}

[materials.steel]
density = 7850.0
youngs_modulus = {E_STEEL}
poisson_ratio = {NU_STEEL}

[[contacts]]
pair = ["beebread", "steel"]
restitution = 0.7
friction = 0.3

[[contacts]]
pair = ["beebread", "beebread"]
restitution = 0.7
friction = 0.3

[effects.granule_collisions]

[contact_model]
kind = "hertz"

[solver]
duration = 0.01
"""


def _case(tmp_path: Path, text: str = CASE, overrides: tuple[str, ...] = ()):
    path = tmp_path / "materials.toml"
    path.write_text(text)
    return validated(path, overrides=list(overrides))


def test_pair_stiffness_is_four_thirds_of_the_effective_modulus(tmp_path: Path) -> None:
    """1/E* = (1 − ν_a²)/E_a + (1 − ν_b²)/E_b by hand: granule-granule E/(2(1 − ν²)) =
    2.8490028e6 Pa, granule-steel 5.6979e6 Pa; k_n = (4/3)E* (rel 1e-12, rounding)."""
    spec = compile_case(_case(tmp_path))
    same = E_BB / (2.0 * (1.0 - NU_BB**2))
    steel = 1.0 / ((1.0 - NU_BB**2) / E_BB + (1.0 - NU_STEEL**2) / E_STEEL)
    assert same == pytest.approx(2.8490028e6, rel=1e-7)
    assert steel == pytest.approx(5.6979e6, rel=1e-4)
    assert spec.contact("beebread", "beebread").stiffness == pytest.approx(4 / 3 * same, rel=1e-12)
    assert spec.contact("beebread", "steel").stiffness == pytest.approx(4 / 3 * steel, rel=1e-12)


def test_hertz_contacts_take_their_own_radii_and_a_flat_wall(tmp_path: Path) -> None:
    """Two granules of radii 2 and 4 mm overlapping by 20 µm, and a 3 mm granule 30 µm into a
    chamber wall of the granules' own material: the kernel's stored energy is
    (2/5)(4/3)E*√R* δ^{5/2} with R* = r_a r_b/(r_a + r_b) and R* = r at the wall, and the
    kernel's first forces (the granules at rest) (4/3)E*√R* δ^{3/2} (rel 1e-9). The wall's R*
    once came from its material's granule radius (r/2 here: 2^{-1/2} of this stiffness) and the
    pair's from one radius per material (two sizes were refused)."""
    spec = compile_case(_case(tmp_path))
    (g,) = spec.granules
    d_pair, d_wall = 2e-5, 3e-5
    r_a, r_b, r_w = 0.002, 0.004, 0.003
    granules = (
        replace(g, position=(-0.06, 0.0), radius=r_a, mass=g.mass * (r_a / g.radius) ** 2),
        replace(g, position=(-0.06 + r_a + r_b - d_pair, 0.0), radius=r_b,
                mass=g.mass * (r_b / g.radius) ** 2),
        replace(g, position=(0.0, -(CHAMBER - r_w + d_wall)), radius=r_w),
    )  # fmt: skip
    sim = Simulation(replace(spec, granules=granules))
    k = spec.contact("beebread", "beebread").stiffness
    r_pair = r_a * r_b / (r_a + r_b)
    pair = 0.4 * k * math.sqrt(r_pair) * d_pair**2.5
    wall = 0.4 * k * math.sqrt(r_w) * d_wall**2.5
    soft = sim.contacts.granules
    assert soft.contact_energy() == pytest.approx(pair + wall, rel=1e-9)
    sim.step()  # at rest: the first step's forces are the springs' alone
    assert soft.f[0, 0] == pytest.approx(-k * math.sqrt(r_pair) * d_pair**1.5, rel=1e-9)
    assert soft.f[2, 1] == pytest.approx(k * math.sqrt(r_w) * d_wall**1.5, rel=1e-9)


@pytest.mark.parametrize(
    ("sets", "problem"),
    [
        (("materials.steel.poisson_ratio=0.51",), "materials.steel.poisson_ratio"),
        (("materials.steel.youngs_modulus=999.0",), "materials.steel.youngs_modulus"),
        (("contact_model.stiffness=1e9",), "contact_model.stiffness already sets"),
        (("contact_model.duration=1e-4",), "contact_model.duration already sets"),
        (("contact_model.duration=1e-4", "contact_model.stiffness=1e9"), "one of stiffness"),
        (
            ('contact_model.kind="linear"', "contact_model.duration=1e-4"),
            "youngs_modulus: sets Hertz stiffness; a linear contact",
        ),
    ],
)
def test_hertz_moduli_refusals(tmp_path: Path, sets: tuple[str, ...], problem: str) -> None:
    with pytest.raises(CaseError, match=problem):
        _case(tmp_path, overrides=sets)


@pytest.mark.parametrize(
    "sets", [("materials.steel.poisson_ratio=0.5",), ("materials.steel.youngs_modulus=1000.0",)]
)
def test_hertz_moduli_at_their_limits_are_taken(tmp_path: Path, sets: tuple[str, ...]) -> None:
    assert compile_case(_case(tmp_path, overrides=sets)).contact("beebread", "steel").stiffness > 0


def test_a_material_without_moduli_is_named(tmp_path: Path) -> None:
    text = CASE.replace(f"youngs_modulus = {E_STEEL}\n", "")
    with pytest.raises(CaseError, match=r"materials\.steel: Hertz contacts .* need youngs_modulus"):
        _case(tmp_path, text)


def test_the_run_summary_states_each_contact(tmp_path: Path) -> None:
    """summary.json's contacts: per contact kind the pair's k_n ((4/3)E*, Pa, as above), Tsuji's
    α for e = 0.7 ending at zero force, the convention named, t_c and t_c over the step, and
    the tangential half-period over the step; the shorter of the two is 50 steps (Mindlin's
    k_t, 1.18 k_n here, oscillates faster than the normal contact: it sets the step)."""
    from perga.analytic.contact import tsuji_alpha
    from perga.cli import main

    path = tmp_path / "materials.toml"
    path.write_text(CASE)
    out = tmp_path / "run"
    assert main(["run", str(path), "-o", str(out), "--quiet", "--set", "solver.duration=1e-3"]) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    contacts = {c["contact"]: c for c in summary["contacts"]}
    assert set(contacts) == {"granule-hammer", "granule-wall", "granule-granule"}
    spec = compile_case(_case(tmp_path))
    for c in contacts.values():
        assert c["stiffness"] == spec.contact(*c["materials"]).stiffness
        assert c["stiffness_unit"].startswith("Pa") and c["restitution"] == 0.7
        assert c["damping"] == pytest.approx(tsuji_alpha(0.7, "force"), rel=1e-15)
        assert "Schwager & Pöschel" in c["convention"]
        assert c["steps_per_contact"] == pytest.approx(c["duration"] / summary["dt"], rel=1e-12)
        half = c["tangential_half_period"]
        assert c["steps_per_tangential_half_period"] == pytest.approx(half / summary["dt"])
    fewest = min(
        min(c["steps_per_contact"], c["steps_per_tangential_half_period"])
        for c in contacts.values()
    )
    assert fewest == pytest.approx(50.0)
    assert min(c["steps_per_contact"] for c in contacts.values()) > 80.0


def test_hertz_by_duration_lasts_that_long_at_the_fastest_speed(tmp_path: Path) -> None:
    """(t_c, e) for Hertz as for linear contacts: with contact_model.duration = 0.1 ms (and no
    moduli), a granule striking the wall head-on at the fastest relative speed lasts 0.1 ms
    (the closed form, rel 1e-9), and every pair shares the k_n that gives it."""
    from perga.model.plan import contact_durations

    text = CASE.replace('kind = "hertz"', 'kind = "hertz"\nduration = 1e-4')
    for modulus in (f"youngs_modulus = {E_BB}\n", f"youngs_modulus = {E_STEEL}\n"):
        text = text.replace(modulus, "")
    case = _case(tmp_path, text)
    assert contact_durations(case)["granule-wall"] == pytest.approx(1e-4, rel=1e-9)
    spec = compile_case(case)
    assert (
        spec.contact("beebread", "steel").stiffness
        == spec.contact("beebread", "beebread").stiffness
    )
