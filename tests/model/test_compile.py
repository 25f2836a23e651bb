"""Case -> System, once: ``load_case`` checks the schema and the names, ``compile_case`` builds
the system (placement, sizes, parts, the step and pair plans) and runs the physical cross-checks
on what it built, every problem at once, each naming the file."""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path

import pytest

from perga.case import CaseError, load_case
from perga.cli import main
from perga.model import compile as compile_module
from perga.model.compile import compile_case, load_system
from perga.model.plan import contact_plan, step_plan

CASES = Path(__file__).resolve().parents[2] / "cases"


def test_loading_checks_the_names_and_compiling_the_physics() -> None:
    """A hammer past the chamber wall is a physical problem: the case loads (schema and names
    are fine) and compiling it names the file, the key and the reach (and the granule the
    smaller wall now overlaps); a material nobody defined is refused by the loading itself."""
    path = CASES / "single-granule.toml"
    case = load_case(path, overrides=["chamber.radius=0.1"])
    with pytest.raises(CaseError) as info:
        compile_case(case)
    reach, wall = info.value.problems
    assert reach.startswith(f"{path}: hammers: a hammer reaches 0.1354 m from the axis")
    assert wall.startswith(f"{path}: granules.placement: granule 0 at (0, 0.11) m overlaps")
    with pytest.raises(CaseError, match="unknown material 'gold'"):
        load_case(path, overrides=['hammers.material="gold"'])


def test_every_physical_problem_at_once() -> None:
    """Three problems of three checks (the shot's placement, an effect, the time step) in one
    error, in the checks' order, each naming the file."""
    path = CASES / "rebound-test.toml"
    overrides = [
        "granules.placement.along=1.0",
        'rotor.plane="vertical"',
        'effects.floor_friction={floor="corotating", friction=0.3}',
        "solver.dt=0.001",
    ]
    with pytest.raises(CaseError) as info:
        compile_case(load_case(path, overrides=overrides))
    keys = [p.removeprefix(f"{path}: ").split(":")[0] for p in info.value.problems]
    assert keys == ["granules.placement.along", "effects.floor_friction", "solver.dt"]


@pytest.mark.parametrize(
    "name", ["separator.toml", "soft-separator.toml", "bee-bread-separator.toml"]
)
def test_the_placement_and_the_plan_are_built_once(name: str, monkeypatch) -> None:
    """``perga run``'s path (load, compile) builds the placement and the step plan once each:
    the checks read what the system is built from (they were each built twice before)."""
    calls = {"initial_state": 0, "step_plan": 0}

    def counted(name, function):
        def wrapper(*args, **kwargs):
            calls[name] += 1
            return function(*args, **kwargs)

        return wrapper

    for function in ("initial_state", "step_plan"):
        monkeypatch.setattr(
            compile_module, function, counted(function, getattr(compile_module, function))
        )
    load_system(CASES / name)
    assert calls == {"initial_state": 1, "step_plan": 1}


def test_the_system_holds_the_plans_the_summary_states() -> None:
    """The system's step plan and pairs' plans are the case's (summary.json states them from
    the system)."""
    case, system = load_system(CASES / "soft-separator.toml")
    assert system.plan == step_plan(case)
    assert [asdict(p) for p in system.pairs] == [
        asdict(p) for p in contact_plan(case, system.granule_dt)
    ]
    _, rigid = load_system(CASES / "separator.toml")
    assert rigid.pairs == ()


def test_a_parameter_set_is_checked_without_a_system(tmp_path, capsys) -> None:
    """A case without a [chamber] has no system (compiling it says so); ``perga validate``
    takes the bundled one and refuses one whose hinged hammers are given a velocity (only a
    free hammer has one)."""
    path = CASES / "paper-fitted.toml"
    with pytest.raises(CaseError, match="chamber: missing"):
        compile_case(load_case(path))
    assert main(["validate", str(path)]) == 0
    bad = tmp_path / "moving.toml"
    bad.write_text(
        path.read_text().replace('mount = "hinged"', 'mount = "hinged"\nvelocity = [1.0, 0.0]')
    )
    assert main(["validate", str(bad)]) == 2
    assert "hammers.velocity: only for mount = 'free'" in capsys.readouterr().err
