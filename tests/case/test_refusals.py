"""Inputs that once ended in a traceback or a hang, each now refused with one line naming the
file, the key and what is allowed (exit 2), or taken: each on both sides of its limit."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from perga.case import CaseError
from perga.cli import main
from perga.geometry.outline import validate_outline
from perga.geometry.units import FARTHEST, GeometryError
from perga.model.compile import validated

ROOT = Path(__file__).resolve().parents[2]
CASES = ROOT / "cases"
ONE = CASES / "single-granule.toml"
SEPARATOR = CASES / "separator.toml"
POSITIONS = "granules.placement.positions"


def refusal(path: Path, *overrides: str) -> list[str]:
    """The problems ``perga validate`` gives for ``path`` with ``overrides`` ([] if taken)."""
    try:
        validated(path, overrides=list(overrides))
    except CaseError as exc:
        return exc.problems
    return []


@pytest.mark.parametrize("extra", [0, 1, 2])
def test_explicit_positions_must_number_the_granules(extra: int) -> None:
    positions = [[0.0, 0.11], [0.0, 0.12], [0.01, 0.11]][: 1 + extra]
    problems = refusal(ONE, f"{POSITIONS}={positions}")
    assert (problems == []) == (extra == 0), problems
    if extra:
        assert problems == [
            f"{ONE}: {POSITIONS}: needs granules.count = 1 entries (got {1 + extra})"
        ]


def test_a_million_granules_against_one_position_is_refused() -> None:
    assert refusal(ONE, "granules.count=1e6") == [
        f"{ONE}: {POSITIONS}: needs granules.count = 1000000 entries (got 1)"
    ]
    assert "granules.count: Input should be less than or equal to 1000000" in "".join(
        refusal(ONE, "granules.count=1000001")
    )


@pytest.mark.parametrize(
    ("key", "value", "taken"),
    [
        ("granules.placement.velocities", "[[1e3, -2.0]]", True),
        ("granules.placement.velocities", "[[nan, 0.0]]", False),
        ("granules.placement.velocities", "[[0.0, -inf]]", False),
        ("granules.placement.angular_velocities", "[inf]", False),
        ("granules.placement.angular_velocities", "[-1e4]", True),
        ("rotor.rpm", "nan", False),
        ("output.every", "3600", True),
        ("output.every", "3600.001", False),
        ("output.every", "inf", False),
        ("output.every", "1e300", False),
        ("output.vtk_every", "1e300", False),
        ("output.checkpoint_every", "3600", True),
        ("output.checkpoint_every", "1e300", False),
    ],
)
def test_numbers_are_finite_and_intervals_at_most_an_hour(key, value, taken) -> None:
    problems = refusal(ONE, f"{key}={value}")
    assert (problems == []) == taken, problems
    if not taken:
        (problem,) = problems
        assert f"{key}" in problem and problem.startswith(f"{ONE} with --set {key}={value}: ")
        assert "finite number" in problem or "less than or equal to 3600" in problem
        assert problem.endswith("]"), "the key's unit and range"


@pytest.mark.parametrize(("angle", "taken"), [(1e3, True), (float("inf"), False)])
def test_a_feed_region_turned_by_a_finite_angle(tmp_path, angle, taken) -> None:
    case = CASES / "bee-bread-separator.toml"
    problems = refusal(case, f"feed.region.angle={angle}")
    assert (problems == []) == taken, problems
    if not taken:
        assert problems == [
            f"{case} with --set feed.region.angle=inf: feed.region.angle: Input should be a finite "
            "number (got inf) [turn of the rectangle, rad (width along +x at 0)]"
        ]


@pytest.mark.parametrize("copies", [1, 2, 20_000])
def test_each_table_is_recorded_once(copies: int) -> None:
    record = '["energy", ' + '"granules", ' * copies + "]"
    problems = refusal(ONE, f"output.record={record}")
    assert (problems == []) == (copies == 1), problems
    if copies > 1:
        (problem,) = problems
        assert "output.record: name each once (granules more than once)" in problem
        assert len(problem) < 1000


@pytest.mark.parametrize("digits", [4300, 4301, 5000])
def test_an_integer_of_thousands_of_digits(digits: int, tmp_path, capsys) -> None:
    """Up to Python's limit (4300 digits) it is a number out of range, beyond it a number
    too long to read: refused either way, naming the key and its range."""
    problems = refusal(ONE, "granules.count=" + "9" * digits)
    (problem,) = problems
    assert "granules.count" in problem and "[number of granules, in [1, 1e6]]" in problem
    assert len(problem) < 400
    path = tmp_path / "case.toml"
    path.write_text(ONE.read_text().replace("count = 1 ", "count = " + "9" * digits + " "))
    assert main(["validate", str(path)]) == 2
    said = capsys.readouterr().err
    assert "granules.count" in said or f"{path}: not valid TOML: an integer of more than" in said


def test_a_contact_pair_given_twice_is_refused() -> None:
    pair = '{pair = ["beebread", "steel"], restitution = 0.5, friction = 0.3}'
    assert refusal(ONE, f"contacts[0]={pair}") == []
    (problem,) = refusal(ONE, f"contacts=[{pair}, {pair}]")
    assert problem.startswith(f"{ONE} with --set contacts=[")
    assert problem.endswith(
        ": contacts[1].pair: ['beebread', 'steel'] is given again (first in contacts[0]): one "
        "entry per pair of materials"
    )


def test_problems_past_twenty_are_counted() -> None:
    many = "[" + ", ".join(["[nan, 0.0]"] * 25) + "]"
    problems = refusal(ONE, f"granules.placement.velocities={many}")
    assert len(problems) == 21 and problems[-1].endswith(": ... and 5 more problems"), problems


@pytest.mark.parametrize(("extent", "taken"), [(FARTHEST, True), (FARTHEST * (1 + 1e-9), False)])
def test_outline_coordinates_within_ten_metres(extent: float, taken: bool) -> None:
    square = np.array([[0.0, 0.0], [extent, 0.0], [extent, extent], [0.0, extent]])
    if taken:
        assert len(validate_outline(square, "square").vertices) == 4
    else:
        with pytest.raises(GeometryError, match=r"square: coordinates must be finite and within"):
            validate_outline(square, "square")


@pytest.mark.parametrize("number", ["1e300", "nan"])
def test_a_chamber_drawn_with_huge_or_no_numbers_is_refused(tmp_path, number) -> None:
    outline = tmp_path / "chamber.txt"
    outline.write_text(f"0 0\n{number} 0\n{number} {number}\n0 {number}\n")
    case = tmp_path / "case.toml"
    text = (CASES / "plate-hammers-soft.toml").read_text()
    case.write_text(
        text.replace('"../geometry/chamber_round.txt"', f'"{outline}"').replace(
            '"../geometry/', f'"{ROOT}/geometry/'
        )
    )
    (problem,) = refusal(case)
    assert problem.startswith(f"{case}: chamber.shape: {outline}: coordinates must be finite")


@pytest.mark.parametrize(("hinge_radius", "taken"), [(0.08, True), (0.0, False)])
def test_a_random_pack_refused_within_seconds(hinge_radius: float, taken: bool) -> None:
    """Hammers hinged on the axis fill the centre of the separator's annulus: the pack cannot
    be made, which it finds out in under 5 s of this process's time."""
    start = time.process_time()
    problems = refusal(SEPARATOR, f"hammers.hinge_radius={hinge_radius}")
    assert time.process_time() - start < 5.0
    assert (problems == []) == taken, problems
    if not taken:
        assert "random placement fitted only 279 of 300 granules" in problems[0]


@pytest.mark.parametrize(("dt", "taken"), [("1e-12", True), ("9.9e-13", False), ("5e-324", False)])
def test_a_given_step_no_finer_than_a_picosecond(dt: str, taken: bool) -> None:
    """A step of 5e-324 s made ``perga run`` overflow counting its steps (1e-300: a run that
    never ends)."""
    problems = refusal(ONE, f"solver.dt={dt}")
    assert (problems == []) == taken, problems
    if not taken:
        (problem,) = problems
        assert f"solver.dt must be in [1e-12, 0.01] s or 'auto' (got {float(dt)})" in problem


@pytest.mark.parametrize("plan_fails", [False, True])
def test_a_step_plan_that_fails_unreported_is_a_problem_not_an_assertion(
    monkeypatch, plan_fails: bool
) -> None:
    """Should the step plan refuse a case that no check reported (the cross-checks name an
    unreachable restitution), validation names it as a problem instead of failing an assert."""
    import perga.model.compile as compile_module

    def refuse(_case):
        raise ValueError("no damping reaches this restitution")

    if plan_fails:
        monkeypatch.setattr(compile_module, "step_plan", refuse)
    problems = refusal(ONE)
    assert problems == (
        [f"{ONE}: solver: no time step for this case (no damping reaches this restitution)"]
        if plan_fails
        else []
    ), problems
