"""Case files and geometry files mutated as a careless user or an adversary would (issue 15,
item 1): every mutant of a bundled case (or of a geometry file it names) either loads, or is
refused with :class:`~perga.case.CaseError` (exit 2 in the CLI, the file and the key named);
never another exception, never a hang. Seeded (``derandomize``), a few hundred mutants in the
default suite; a mutant that loads is also mapped to the system and built (``Simulation``), as
``perga run`` does next."""

from __future__ import annotations

import math
import re
import time
import tomllib
from pathlib import Path
from typing import Any

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from perga.case import CaseError
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case, validated
from tests.value_paths import value_paths

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = {p.name: tomllib.loads(p.read_text()) for p in sorted((ROOT / "cases").glob("*.toml"))}
SECONDS = 10.0
"""Longest a mutant may take to load and map (the slowest bundled case takes about 1 s), once
numba has compiled what the bundled cases build (``compiled``)."""


@pytest.fixture(scope="module")
def compiled() -> None:
    """Every bundled case built once, so that numba's one-time compilation (11 s for the soft
    kernel in a fresh clone with another job on the second core) is not timed as a mutant's."""
    for name in BUNDLED:
        case = validated(ROOT / "cases" / name)
        if case.chamber is not None:
            Simulation(compile_case(case))


ODD_VALUES = st.sampled_from(
    [
        math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 5e-324, 1e-300, 1e300, 10**30, -(10**30),
        1e-12, 1e-9, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 0.5, 2.0,
        0, 1, True, False, "", "1500", "auto", "∞", "\x00", "x" * 10_000, [], [1.0], [[]],
        {}, {"kind": "nope"}, [[0.0, 0.0]] * 3,
    ]
)  # fmt: skip


def mutated(data: dict, path: tuple, action: str, value: Any) -> dict:
    """A deep copy of ``data`` with the value at ``path`` deleted or replaced by ``value``."""
    copy = tomllib.loads(tomli_w.dumps(data))
    parent = copy
    for key in path[:-1]:
        parent = parent[key]
    if action == "delete":
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    return copy


@st.composite
def mutants(draw: st.DrawFn) -> tuple[str, str]:
    """(name, TOML text) of a bundled case with one to three values deleted or replaced."""
    name = draw(st.sampled_from(sorted(BUNDLED)))
    data = BUNDLED[name]
    for _ in range(draw(st.integers(1, 3))):
        paths = value_paths(data)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        action = draw(st.sampled_from(["delete", "replace"]))
        data = mutated(data, path, action, draw(ODD_VALUES))
    return name, tomli_w.dumps(data)


@settings(
    max_examples=300,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(mutant=mutants())
def test_a_mutated_case_loads_or_is_refused_with_its_problems(mutant, tmp_path_factory, compiled):
    name, text = mutant
    path = tmp_path_factory.mktemp("fuzz") / name
    path.write_text(text, encoding="utf-8")
    start = time.monotonic()
    try:
        case = validated(path)
    except CaseError as exc:
        assert exc.problems and all(p.startswith(f"{path}: ") for p in exc.problems)
    else:
        if case.chamber is not None:
            Simulation(compile_case(case))
    assert time.monotonic() - start < SECONDS


@settings(max_examples=50, derandomize=True, deadline=None)
@given(garbage=st.binary(max_size=2000))
def test_bytes_that_are_no_case_file_are_refused(garbage, tmp_path_factory):
    path = tmp_path_factory.mktemp("fuzz") / "garbage.toml"
    path.write_bytes(garbage)
    try:
        validated(path)
    except CaseError as exc:
        assert all(p.startswith(f"{path}: ") for p in exc.problems)


REFERENCES = [
    (case.name, line.split('path = "')[1].split('"')[0])
    for case in sorted((ROOT / "cases").glob("*.toml"))
    for line in case.read_text().splitlines()
    if 'kind = "file", path = "' in line
]
"""(case, relative geometry path) of every geometry file a bundled case refers to."""
NUMBER = re.compile(rb"-?\d+(\.\d+)?([eE][-+]?\d+)?")


@st.composite
def broken_geometry(draw: st.DrawFn) -> tuple[str, str, bytes]:
    """(case, the geometry path it names, the file's bytes broken): cut short, bytes
    overwritten, or (text files) a number replaced by nan, inf, a huge, tiny or negative value
    or a word."""
    case, relative = draw(st.sampled_from(REFERENCES))
    data = (ROOT / "cases" / relative).resolve().read_bytes()
    how = draw(st.sampled_from(["cut", "overwrite", "number"]))
    if how == "cut":
        data = data[: draw(st.integers(0, len(data)))]
    elif how == "overwrite":
        at = draw(st.integers(0, max(len(data) - 1, 0)))
        data = data[:at] + draw(st.binary(min_size=1, max_size=64)) + data[at + 64 :]
    else:
        numbers = list(NUMBER.finditer(data[:200_000]))
        if numbers:
            m = draw(st.sampled_from(numbers))
            word = draw(st.sampled_from([b"nan", b"inf", b"1e300", b"1e-300", b"-5", b"0", b"x"]))
            data = data[: m.start()] + word + data[m.end() :]
    return case, relative, data


@settings(
    max_examples=150,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture],
)
@given(broken=broken_geometry())
def test_a_broken_geometry_file_loads_or_is_refused(broken, tmp_path_factory):
    """A bundled case pointing at a broken copy of its geometry file loads (and builds) or is
    refused with CaseError, never another exception."""
    case, relative, data = broken
    folder = tmp_path_factory.mktemp("geometry")
    geometry = folder / Path(relative).name
    geometry.write_bytes(data)
    text = (ROOT / "cases" / case).read_text().replace(f'"{relative}"', f'"{geometry}"')
    path = folder / case
    path.write_text(text)
    start = time.monotonic()
    try:
        loaded = validated(path)
    except CaseError as exc:
        assert exc.problems
    else:
        Simulation(compile_case(loaded))
    assert time.monotonic() - start < SECONDS
