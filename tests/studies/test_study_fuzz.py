"""Study files mutated as a careless user would (issue 15, item 1): every mutant of a valid
study either loads, and its design expands to points, or is refused with
:class:`~perga.studies.study_file.StudyError` whose every problem names the file; never another
exception. Seeded, in the default suite."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from perga.studies.design import points
from perga.studies.study_file import StudyError, load_study
from tests.value_paths import value_paths

ROOT = Path(__file__).resolve().parents[2]
STUDY = {
    "case": str(ROOT / "cases" / "rebound-test.toml"),
    "design": "grid",
    "samples": 16,
    "replicates": 2,
    "seed": 0,
    "metrics": ["first_impact_restitution", "first_impact_rebound_angle_centre"],
    "parameters": {
        "granules.placement.angle": {"values": [0.2, 0.6, 1.0, 1.3]},
        "contacts.granule-hammer.friction": {"range": [0.1, 0.5], "points": 3},
    },
}
"""The study of the study_file module's docstring, its case made absolute."""
ODD = st.sampled_from(
    [
        math.nan, math.inf, -1, 0, 1, 2, 10**9, 0.5, -0.5, True, "", "lhs", "sobol", "log",
        "grid", "nope", "first_impact_restitution", "x" * 1000, [], [1.0], [0.5, 0.1],
        [0.1, 0.5], {}, {"values": []}, {"range": [1, 0]},
    ]
)  # fmt: skip


@st.composite
def mutants(draw: st.DrawFn) -> dict:
    data = tomllib.loads(tomli_w.dumps(STUDY))
    for _ in range(draw(st.integers(1, 3))):
        path = draw(st.sampled_from(value_paths(data)))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        if draw(st.booleans()):
            del parent[path[-1]]
        else:
            parent[path[-1]] = copy.deepcopy(draw(ODD))  # the strategy's own stays intact
    return data


@settings(
    max_examples=200,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(mutant=mutants())
def test_a_mutated_study_loads_or_is_refused_with_its_problems(mutant, tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "study.toml"
    path.write_text(tomli_w.dumps(mutant), encoding="utf-8")
    try:
        study = load_study(path)
    except StudyError as exc:
        assert exc.problems and all(p.startswith(f"{path}") for p in exc.problems)
    else:
        assert points(study)


@pytest.mark.parametrize("case", ["x" * 1000, str(ROOT / "cases" / "rebound-test.toml")])
def test_a_case_name_the_file_system_refuses_is_a_study_error(case, tmp_path):
    """Found by the fuzz test: a 1,000-character case name raised OSError (ENAMETOOLONG) from
    ``Path.is_file``; the bundled case's name (the other side) loads."""
    path = tmp_path / "study.toml"
    path.write_text(tomli_w.dumps(STUDY | {"case": case}), encoding="utf-8")
    if len(case) == 1000:
        with pytest.raises(StudyError, match="case: cannot use"):
            load_study(path)
    else:
        assert load_study(path).case.name == "rebound-test.toml"
