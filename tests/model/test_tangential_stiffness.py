"""The tangential stiffness of soft contacts (issue 19, item 3): Mindlin's from the materials or
a given k_t/k_n, the ratio's range an elastic solid's, and the step plan resolving a sticking
contact's tangential oscillation as well as its normal contact. Limits and half-periods are
worked out here by hand from the case's numbers."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from perga.case import CaseError
from perga.contact.soft.build import kernel_table, polygon_table
from perga.contact.soft.laws import P_KN, P_KT
from perga.model.compile import compile_case
from perga.model.plan import contact_plan, fastest_relative_speed, step_plan

from .test_materials import CASE, E_BB, E_STEEL, NU_BB, NU_STEEL, _case

K_LINEAR = 2.0e4  # N/m
LINEAR = (
    CASE.replace(f"youngs_modulus = {E_BB}\n", "")
    .replace(f"youngs_modulus = {E_STEEL}\n", "")
    .replace('kind = "hertz"', f'kind = "linear"\nstiffness = {K_LINEAR}')
)
MASS = 1300.0 * math.pi * 0.003**2 * 0.01  # kg: the granule, 3 mm, 10 mm thick


def _mindlin(e_a: float, nu_a: float, e_b: float, nu_b: float) -> float:
    """8G*/((4/3)E*) by hand."""
    g_star = 1 / ((2 - nu_a) * 2 * (1 + nu_a) / e_a + (2 - nu_b) * 2 * (1 + nu_b) / e_b)
    e_star = 1 / ((1 - nu_a**2) / e_a + (1 - nu_b**2) / e_b)
    return 8 * g_star / (4 / 3 * e_star)


def test_hertz_from_the_materials_takes_mindlins_ratio(tmp_path: Path) -> None:
    """Each pair its own 6G*/E* (1e-12): granule-granule 3(1 − ν)/(2 − ν) = 1.1818, granule-steel
    1.1820; k_t = ratio·k_n in the kernel's table and in the hammers' (polygons') table."""
    spec = compile_case(_case(tmp_path))
    same = spec.contact("beebread", "beebread")
    steel = spec.contact("beebread", "steel")
    assert same.tangential_ratio == pytest.approx(3 * 0.65 / 1.65, rel=1e-12)
    assert same.tangential_ratio == pytest.approx(_mindlin(E_BB, NU_BB, E_BB, NU_BB), rel=1e-12)
    assert steel.tangential_ratio == pytest.approx(
        _mindlin(E_BB, NU_BB, E_STEEL, NU_STEEL), rel=1e-12
    )
    row = kernel_table(spec, ["beebread"])[0, 0]
    assert row[P_KT] == pytest.approx(same.tangential_ratio * row[P_KN], rel=1e-15)
    hammer = polygon_table(spec, ["beebread"], ["steel"])
    assert hammer.k_t[0, 0] == pytest.approx(steel.tangential_ratio * hammer.k_n[0, 0], rel=1e-15)


@pytest.mark.parametrize(
    ("text", "sets", "ratio"),
    [
        (CASE, ("contact_model.tangential_ratio=0.5",), 0.5),
        (CASE, ('contact_model.tangential_ratio="mindlin"',), 3 * 0.65 / 1.65),
        (LINEAR, (), 2 / 7),
        (LINEAR, ("contact_model.tangential_ratio=1.2",), 1.2),
    ],
)
def test_a_given_ratio_or_the_default(tmp_path: Path, text: str, sets, ratio: float) -> None:
    spec = compile_case(_case(tmp_path, text, sets))
    assert spec.contact("beebread", "beebread").tangential_ratio == pytest.approx(ratio, rel=1e-12)


def test_hertz_by_a_shared_duration_keeps_two_sevenths(tmp_path: Path) -> None:
    text = CASE.replace('kind = "hertz"', 'kind = "hertz"\nduration = 1e-4')
    for modulus in (f"youngs_modulus = {E_BB}\n", f"youngs_modulus = {E_STEEL}\n"):
        text = text.replace(modulus, "")
    spec = compile_case(_case(tmp_path, text))
    assert spec.contact("beebread", "steel").tangential_ratio == 2 / 7


@pytest.mark.parametrize("factor", [1.0, 1.01])
@pytest.mark.parametrize(("text", "secant"), [(LINEAR, 1.0), (CASE, 1.5)], ids=["linear", "hertz"])
def test_the_ratio_is_capped_where_an_elastic_solid_is(
    tmp_path: Path, text, secant, factor
) -> None:
    """An elastic solid's k_t/k_n at ν → −1: 2(1 − ν)/(2 − ν) = 4/3 on tangents (linear),
    1.5 times that, 3(1 − ν)/(2 − ν) = 2, on Hertz's secant (whose k_n√δ is 2/3 of the
    tangent's 2E*√(Rδ)); taken at the limit, refused 1 % above."""
    nu = -1.0
    limit = secant * 2 * (1 - nu) / (2 - nu)
    sets = (f"contact_model.tangential_ratio={factor * limit!r}",)
    if factor > 1:
        with pytest.raises(CaseError, match=r"contact_model.*tangential_ratio.*outside"):
            _case(tmp_path, text, sets)
    else:
        assert compile_case(_case(tmp_path, text, sets)).contact("beebread", "steel")


@pytest.mark.parametrize(
    ("text", "sets", "problem"),
    [
        (LINEAR, ('contact_model.tangential_ratio="mindlin"',), "'mindlin' is for kind = 'hertz'"),
        (LINEAR, ("contact_model.tangential_ratio=-0.01",), "outside"),
        (
            CASE.replace(f"poisson_ratio = {NU_STEEL}\n", ""),
            ('contact_model.tangential_ratio="mindlin"', "contacts.beebread-steel.stiffness=1e9"),
            r"materials\.steel: contact_model\.tangential_ratio = 'mindlin' needs poisson_ratio",
        ),
    ],
)
def test_mindlin_refusals(tmp_path: Path, text: str, sets, problem: str) -> None:
    with pytest.raises(CaseError, match=problem):
        _case(tmp_path, text, sets)


def test_mindlin_with_a_shared_stiffness_is_refused(tmp_path: Path) -> None:
    text = CASE.replace(f"youngs_modulus = {E_BB}\n", "").replace(
        f"youngs_modulus = {E_STEEL}\n", ""
    )
    sets = ('contact_model.tangential_ratio="mindlin"', "contact_model.stiffness=1e7")
    with pytest.raises(CaseError, match="'mindlin' takes k_t/k_n from the materials"):
        _case(tmp_path, text, sets)


def _linear_half_period(ratio: float) -> float:
    """π/ω_t of two sticking granules (the shortest: m_eff = m/2), ω_t² = 6k_t/m, s."""
    return math.pi / math.sqrt(6 * ratio * K_LINEAR / MASS)


def test_the_plan_resolves_the_tangential_half_period(tmp_path: Path) -> None:
    """Linear, k_t/k_n = 1.2: the granule pair's half-period π/√(6k_t/m) is shorter than its
    contact π/(ω_n√(1 − ζ²)), ω_n² = 2k_n/m, and the step is a 50th of it (1e-12)."""
    case = _case(tmp_path, LINEAR, ("contact_model.tangential_ratio=1.2",))
    plan = step_plan(case)
    half = _linear_half_period(1.2)
    assert plan.tangential_half_period == pytest.approx(half, rel=1e-12)
    assert plan.contact_duration > 1.5 * half
    assert plan.granule == pytest.approx(half / 50, rel=1e-12)
    assert plan.governed_by == "contact"


def test_hertz_half_period_at_the_peak_overlap(tmp_path: Path) -> None:
    """Hertz from the materials, granule-granule (R* = r/2, m_eff = m/2) and granule-wall (the
    chamber is of the granules' material; R* = r, m_eff = m): k_t = ratio·(4/3)E*√(R*δ_max),
    E* = E/(2(1 − ν²)), δ_max from ½m_eff v² = (2/5)(4/3)E*√R* δ_max^{5/2} at the fastest
    relative speed; the half-period π/√(3k_t/m_eff) (1e-12)."""
    case = _case(tmp_path)
    v = fastest_relative_speed(case)
    plans = {p.contact: p for p in contact_plan(case, 1.0)}
    for name, r_eff, m_eff in (
        ("granule-granule", 0.0015, MASS / 2),
        ("granule-wall", 0.003, MASS),
    ):
        k = 4 / 3 * E_BB / (2 * (1 - NU_BB**2)) * math.sqrt(r_eff)
        peak = (0.5 * m_eff * v * v / (0.4 * k)) ** 0.4
        k_t = 3 * 0.65 / 1.65 * k * math.sqrt(peak)
        half = math.pi / math.sqrt(3 * k_t / m_eff)
        assert plans[name].tangential_half_period == pytest.approx(half, rel=1e-12)


@pytest.mark.parametrize(("factor", "side"), [(0.99, "taken"), (1.01, "refused")])
def test_a_given_step_needs_ten_per_tangential_half_period(
    tmp_path: Path, factor: float, side: str
) -> None:
    dt = factor * _linear_half_period(1.2) / 10
    sets = ("contact_model.tangential_ratio=1.2", f"solver.dt={dt!r}")
    if side == "refused":
        with pytest.raises(CaseError, match="tangential oscillation"):
            _case(tmp_path, LINEAR, sets)
    else:
        assert step_plan(_case(tmp_path, LINEAR, sets)).granule == dt
