"""The automatic step honours ``contact_model.steps_per_contact`` where a sticking contact's
tangential half-period governs it: dt = half-period / steps_per_contact, at values other than
the default 50, for the linear law (k_t/k_n = 1.2) and for Hertz from the materials (Mindlin's
ratio)."""

from __future__ import annotations

from pathlib import Path

import pytest

from perga.model.plan import contact_durations, contact_plan, contact_steps, step_plan

from .test_materials import CASE, _case
from .test_tangential_stiffness import LINEAR

LAWS = {"linear": (LINEAR, ("contact_model.tangential_ratio=1.2",)), "hertz": (CASE, ())}


@pytest.mark.parametrize("law", LAWS)
@pytest.mark.parametrize("steps", [20.0, 137.0])
def test_the_tangential_half_period_takes_steps_per_contact_steps(
    tmp_path: Path, law: str, steps: float
) -> None:
    """The tangential half-period is the shortest span (it governs: below every t_c over its
    own steps); the granule step is it over steps_per_contact, and the pairs' plan says so
    (1e-12: one division)."""
    text, sets = LAWS[law]
    case = _case(tmp_path, text, (*sets, f"contact_model.steps_per_contact={steps!r}"))
    plan = step_plan(case)
    normal = min(t / contact_steps(case, name) for name, t in contact_durations(case).items())
    assert plan.tangential_half_period / steps < normal
    assert plan.governed_by == "contact"
    assert plan.granule == pytest.approx(plan.tangential_half_period / steps, rel=1e-12)
    fewest = min(p.steps_per_tangential_half_period for p in contact_plan(case, plan.granule))
    assert fewest == pytest.approx(steps, rel=1e-12)
