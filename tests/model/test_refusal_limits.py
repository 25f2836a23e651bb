"""Every numeric refusal of the case checks on both sides of its limit (issue 18, item 2): the
limit worked out here from the case's numbers and the physics that sets it, never from the
code under test; 0.99 and 1.01 of it (the time-step limits: tests/model/test_plan.py)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from perga.case import CaseError
from perga.model.compile import validated

CASES = Path(__file__).resolve().parents[2] / "cases"
SIDES = [(0.99, "below"), (1.01, "above")]


def _problems(path: Path, sets: list[str]) -> str:
    """The refusal's text, or "" when the case is taken."""
    try:
        validated(path, overrides=sets)
    except CaseError as exc:
        return str(exc)
    return ""


@pytest.mark.parametrize(("factor", "side"), SIDES)
def test_a_hammer_reaching_the_wall(factor: float, side: str) -> None:
    """single-granule's plate, 60 × 20 mm hinged 5 mm from its end at 80 mm, reaches
    √((0.08 + 0.055)² + 0.01²) m radially; a chamber of that radius is refused, 1 % larger
    taken."""
    reach = math.hypot(0.08 + 0.055, 0.01)
    said = _problems(CASES / "single-granule.toml", [f"chamber.radius={factor * reach!r}"])
    assert ("past the chamber wall" in said) == (side == "below"), said


@pytest.mark.parametrize(("factor", "side"), SIDES)
def test_a_random_pack_too_dense(factor: float, side: str) -> None:
    """A random pack may fill at most half its annulus (random sequential addition jams near
    0.547): 100 granules of 2.5 mm between 140 mm and R_o fill 100 r²/(R_o² − R_i²); R_o set
    for a fill of 0.99 and 1.01 of one half."""
    fill = 0.5 * factor
    outer = math.sqrt(0.14**2 + 100 * 0.0025**2 / fill)
    placement = f"{{kind='random', inner_radius=0.14, outer_radius={outer!r}}}"
    sets = ["granules.count=100", f"granules.placement={placement}"]
    said = _problems(CASES / "single-granule.toml", sets)
    assert ("a random pack needs <= 50%" in said) == (side == "above"), said


@pytest.mark.parametrize(("factor", "side"), SIDES)
def test_comb_cells_too_close(factor: float, side: str) -> None:
    """Comb cells must be at least the largest granule's diameter apart: bee-bread-separator's
    granules reach 2.65 mm, so a pitch of 5.3 mm is the limit."""
    sets = [f"granules.placement.pitch={factor * 2 * 0.00265!r}"]
    said = _problems(CASES / "bee-bread-separator.toml", sets)
    assert ("cannot hold granules" in said) == (side == "below"), said


@pytest.mark.parametrize(("factor", "side"), SIDES)
def test_a_stated_overlap_past_half_a_radius(factor: float, side: str) -> None:
    """A placement's allowed overlap must stay below half the smallest radius, 1.25 mm for
    single-granule's 2.5 mm granule (its granule touches nothing, so the smaller is taken)."""
    said = _problems(
        CASES / "single-granule.toml", [f"granules.placement.overlap={factor * 0.00125!r}"]
    )
    assert ("below half the smallest radius" in said) == (side == "above"), said


@pytest.mark.parametrize(("factor", "side"), SIDES)
def test_a_restitution_a_clamped_linear_contact_cannot_reach(factor: float, side: str) -> None:
    """A linear spring-dashpot whose force is clamped at zero cannot rebound slower than e⁻²
    of its approach (Schwager & Pöschel 2007: e → e^{−2} as the damping goes critical)."""
    e = factor * math.exp(-2.0)
    said = _problems(CASES / "soft-separator.toml", [f"contacts[0].restitution={e!r}"])
    assert ("out of reach of a linear contact" in said) == (side == "below"), said
