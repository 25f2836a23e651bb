"""A new contact law is one module and one registry line: the law of ``toy_law.py``, kept in the
tests, registered by one line, is taken by the case file, the checks, the step plan and the
kernel, and a run shows its damping.

The case is the bundled soft single granule (tests/test_soft_run.py), whose linear law gives
the measured restitution within 0.5 % of e at the hinged hammer; the toy's promise is held to the
same 0.5 %. For e = 0.5 it promises 0.5503, 10 % above the linear law's 0.5.
"""

import json
import math

import pytest

from perga.analytic.contact import damping_ratio, restitution
from perga.case import CaseError
from perga.case.reference import json_schema, markdown_reference
from perga.contact.laws import LAWS
from perga.model import SoftContactSpec
from perga.model.compile import validated
from perga.model.plan import contact_plan, contact_steps, step_plan, steps_for_damping
from tests.test_soft_run import SOFT, soft_run
from tests.test_soft_run import restitution as measured

TOY = "tests.contact.laws.toy_law:OverlapDamped"


@pytest.fixture
def toy(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(LAWS, "toy", TOY)  # the one line


def promised(e: float) -> float:
    """The toy's rebound with the force clamped at zero: ζ of the zero-overlap end, taken to
    the zero-force end (Schwager & Pöschel 2007)."""
    return restitution(damping_ratio(e, "overlap"), "force")


def test_a_run_of_the_new_law_rebounds_as_it_promises(tmp_path, toy) -> None:
    assert promised(0.5) == pytest.approx(0.5503, abs=1e-4)
    summary, impacts = soft_run(
        tmp_path,
        replace={'kind = "linear"': 'kind = "toy"', "restitution = 0.7": "restitution = 0.5"},
    )
    assert summary["status"] == "completed"
    assert summary["time_step"]["contact_model"] == "toy"
    plan = {pair["contact"]: pair for pair in summary["contacts"]}
    assert plan["granule-hammer"]["damping"] == damping_ratio(0.5, "overlap")
    # its own duration -> stiffness rule: a granule on the wall lasts contact_model.duration
    assert plan["granule-wall"]["duration"] == pytest.approx(1e-4, rel=1e-12)
    assert measured(impacts[0]) == pytest.approx(promised(0.5), rel=0.005)


def test_the_new_law_reaches_the_restitutions_it_says(tmp_path, toy) -> None:
    """e = 0.1 is below e⁻² ≈ 0.135: out of the linear law's reach with the force clamped at
    zero, in the toy's (its ζ < 1 for every e > 0)."""
    text = SOFT.read_text().replace("restitution = 0.7", "restitution = 0.1")
    path = tmp_path / "case.toml"
    path.write_text(text)
    with pytest.raises(CaseError, match="out of reach of a linear contact"):
        validated(path)
    path.write_text(text.replace('kind = "linear"', 'kind = "toy"'))
    case = validated(path)
    (hammer, *_) = contact_plan(case, step_plan(case).granule)
    zeta = damping_ratio(0.1, "overlap")
    assert hammer.damping == zeta < 1.0
    assert math.isfinite(hammer.duration)
    # its ζ = 0.59 takes 92 steps per contact, not 50 (steps_for_damping)
    assert contact_steps(case, "granule-hammer") == steps_for_damping(zeta, 50.0) > 90.0


def test_the_schema_lists_the_registered_laws(toy) -> None:
    kind = json.loads(json_schema())["$defs"]["ContactModelTable"]["properties"]["kind"]
    assert kind["enum"] == ["rigid", "linear", "hertz", "toy"]
    assert "| `kind` | `one of 'rigid', 'linear', 'hertz', 'toy'` |" in markdown_reference()


def test_the_system_takes_a_registered_law(monkeypatch) -> None:
    with pytest.raises(ValueError, match=r"a contact law, one of linear, hertz \(got 'toy'\)"):
        SoftContactSpec("toy")
    monkeypatch.setitem(LAWS, "toy", TOY)
    assert SoftContactSpec("toy").kind == "toy"
