"""A soft contact pair's own stiffness in [[contacts]] (issue 17, item 7): by ``duration`` or
``stiffness``, instead of [contact_model]'s, which the other pairs keep."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from perga.case import CaseError
from perga.model.compile import compile_case, validated
from perga.model.plan import contact_durations
from tests.case_text import case_text

SOFT = Path(__file__).resolve().parents[2] / "cases" / "soft-separator.toml"
RIGID = SOFT.with_name("separator.toml")
GRANULES = 1  # contacts[1]: beebread-beebread in both cases


def test_a_pairs_duration_sets_only_that_pairs_contacts() -> None:
    """A duration D for granule-granule contacts is that of a granule striking a rigid wall; two
    granules (reduced mass m/2) then touch for D/√2 (a linear contact's duration goes as
    √(m_eff/k) at a given e; to 1e-12). The hammer's and the wall's contacts keep theirs."""
    case = validated(SOFT)
    assert case.contacts[GRANULES].pair == ("beebread", "beebread")
    before = contact_durations(case)
    D = 2.5e-4
    own = validated(SOFT, overrides=[f"contacts[{GRANULES}].duration={D}"])
    after = contact_durations(own)
    assert after["granule-granule"] == pytest.approx(D / math.sqrt(2), rel=1e-12)
    for kind in ("granule-hammer", "granule-wall"):
        assert after[kind] == before[kind]


def test_a_pairs_stiffness_reaches_the_kernels_contact() -> None:
    own = validated(SOFT, overrides=[f"contacts[{GRANULES}].stiffness=12345.0"])
    stiffness = [c.stiffness for c in compile_case(own).contacts]
    shared = [c.stiffness for c in compile_case(validated(SOFT)).contacts]
    assert stiffness.pop(GRANULES) == 12345.0
    shared.pop(GRANULES)
    assert stiffness == shared


@pytest.mark.parametrize(
    ("sets", "taken"),
    [
        ([f"contacts[{GRANULES}].duration=0.99e-9"], False),
        ([f"contacts[{GRANULES}].duration=1e-9"], True),
        ([f"contacts[{GRANULES}].duration=0.01"], True),
        ([f"contacts[{GRANULES}].duration=0.0101"], False),
        ([f"contacts[{GRANULES}].stiffness=0.99"], False),
        ([f"contacts[{GRANULES}].stiffness=1.0"], True),
    ],
)
def test_a_pairs_stiffness_on_both_sides_of_its_limits(sets: list[str], taken: bool) -> None:
    if taken:
        validated(SOFT, overrides=sets)
    else:
        with pytest.raises(CaseError, match=rf"contacts\[{GRANULES}\]\.(duration|stiffness)"):
            validated(SOFT, overrides=sets)


def test_a_pairs_stiffness_refusals() -> None:
    both = [f"contacts[{GRANULES}].duration=1e-4", f"contacts[{GRANULES}].stiffness=1e4"]
    with pytest.raises(CaseError, match=r"duration \(s\) or its stiffness, not both"):
        validated(SOFT, overrides=both)
    with pytest.raises(CaseError, match=rf"contacts\[{GRANULES}\]\.duration: .*rigid contacts"):
        validated(RIGID, overrides=[f"contacts[{GRANULES}].duration=1e-4"])


def test_hertz_pairs_with_their_own_stiffness_need_no_moduli(tmp_path: Path) -> None:
    """Hertz without a shared stiffness takes each pair's from its materials' moduli, unless the
    pair has its own: every pair given its own → taken without moduli; one left → refused,
    naming the materials that then need them."""
    text = case_text(SOFT).replace('kind = "linear"\nduration = 1e-4', 'kind = "hertz"')
    assert 'kind = "hertz"' in text
    case = tmp_path / "hertz.toml"
    case.write_text(text)
    both = ["contacts[0].duration=1e-4", f"contacts[{GRANULES}].stiffness=1e7"]
    validated(case, overrides=both)
    with pytest.raises(CaseError, match=r"materials\.beebread: Hertz contacts without"):
        validated(case, overrides=both[:1])
