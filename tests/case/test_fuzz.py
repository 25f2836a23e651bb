"""Case files and geometry files mutated as a careless user or an adversary would: every mutant
of a bundled case (or of a geometry file it names) either loads, or is refused with
:class:`~perga.case.CaseError` (exit 2 in the CLI, the file and the key named); never another
exception, never a hang. Seeded (``derandomize``), a few hundred mutants in the default suite; a
mutant that loads is also mapped to the system and built (``Simulation``), as ``perga run`` does
next. The slow fuzz goes further: mutants over every section of the schema (keys inserted, whole
tables grafted from another bundled case) and ``--set`` overrides of any key, each validated
and, if accepted, run for a few steps in a worker process with a timeout
(:mod:`tests.case.fuzz_worker`)."""

from __future__ import annotations

import itertools
import math
import re
import time
import tomllib
import typing
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
import tomli_w
from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st
from pydantic_core import PydanticUndefined

from perga.case import CaseError
from perga.case.schema import Case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case, validated
from tests.case.fuzz_worker import Worker
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


def schema_keys(model: type = Case, prefix: tuple = ()) -> list[tuple[tuple, Any]]:
    """(path, field) of every key of the case-file schema, tables included: a member of a union
    (placement kinds, hammer shapes) gives its keys, ``[materials.NAME]`` is named "NAME" and
    a list of tables (``[[contacts]]``) is indexed 0."""
    keys = []
    for name, field in model.model_fields.items():
        path = (*prefix, name)
        keys.append((path, field))
        annotation = field.annotation
        if typing.get_origin(annotation) is dict:
            path = (*path, "NAME")
        elif typing.get_origin(annotation) is list:
            path = (*path, 0)
        args = typing.get_args(annotation) or (annotation,)
        members = [a for arg in args for a in (typing.get_args(arg) or (arg,))]
        for member in members:
            if isinstance(member, type) and hasattr(member, "model_fields"):
                keys += schema_keys(member, path)
    return keys


SCHEMA_KEYS = schema_keys()
"""Every key of the schema, every section's (sizes, feed, comb, damage, outlet, materials,
checkpoints, threads, placement, geometry, output...)."""


def near_limits(field: Any) -> list[Any]:
    """Values at, just inside and just outside each of a field's limits, and its default."""
    values = [] if field.default in (None, PydanticUndefined) else [field.default]
    for limit in field.metadata:
        for bound in (getattr(limit, a, None) for a in ("ge", "gt", "le", "lt")):
            if isinstance(bound, int | float):
                step = 1 if isinstance(bound, int) else abs(bound) * 1e-6 or 1e-12
                values += [bound, bound - step, bound + step, bound * 10, -bound]
    return values


def named(path: tuple, data: dict) -> tuple:
    """``path`` with "NAME" the name of one of the case's materials."""
    table = data.get("materials")
    materials = sorted(table) if isinstance(table, dict) and table else ["steel"]
    return tuple(materials[0] if part == "NAME" else part for part in path)


@st.composite
def key_and_value(draw: st.DrawFn, data: dict) -> tuple[tuple, Any]:
    """A key of the schema (``data``'s material names) and a value for it: near its limits
    (so that some mutants run) or odd."""
    path, field = draw(st.sampled_from(SCHEMA_KEYS))
    limits = near_limits(field)
    values = st.one_of(st.sampled_from(limits), ODD_VALUES) if limits else ODD_VALUES
    return named(path, data), draw(values)


def inserted(data: dict, path: tuple, value: Any) -> dict:
    """A deep copy of ``data`` with ``value`` at ``path``, its tables created (lists grown by
    one table where the index is past their end); ``data`` itself if a value on the way is not
    a table or list."""
    copy = tomllib.loads(tomli_w.dumps(data))
    node: Any = copy
    for key, following in itertools.pairwise(path):
        if isinstance(node, list) and isinstance(key, int):
            if key >= len(node):
                node.append({})
            node = node[min(key, len(node) - 1)]
        elif isinstance(node, dict):
            node = node.setdefault(key, [] if isinstance(following, int) else {})
        else:
            return data
    if isinstance(node, dict) and isinstance(path[-1], str):
        node[path[-1]] = value
    elif isinstance(node, list) and isinstance(path[-1], int):
        node.append(value)
    else:
        return data
    return copy


SECTIONS = [
    ("feed",), ("outlet",), ("damage",), ("granules", "size"), ("granules", "placement"),
    ("granules",), ("materials",), ("contacts",), ("contact_model",), ("effects",),
    ("chamber",), ("hammers", "shape"), ("hammers",), ("rotor",), ("solver",), ("output",),
]  # fmt: skip
"""Tables a mutant may take whole from another bundled case (where one has it)."""


def section(data: dict, path: tuple) -> Any:
    """The table at ``path`` of ``data``, or None."""
    for key in path:
        if not isinstance(data, dict) or key not in data:
            return None
        data = data[key]
    return data


@st.composite
def mutants(draw: st.DrawFn, actions: tuple[str, ...] = ("delete", "replace")) -> tuple[str, str]:
    """(name, TOML text) of a bundled case with one to three ``actions``: a value deleted or
    replaced by an odd one; a key of any section of the schema inserted (``insert``); a whole
    table taken from another bundled case (``graft``); a list's entries repeated (``repeat``:
    more positions than granules, a table recorded twice)."""
    name = draw(st.sampled_from(sorted(BUNDLED)))
    data = BUNDLED[name]
    for _ in range(draw(st.integers(1, 3))):
        action = draw(st.sampled_from(actions))
        paths = value_paths(data)
        if action == "insert":
            path, value = draw(key_and_value(data))
            data = inserted(data, path, value)
        elif action == "graft":
            path = draw(st.sampled_from(SECTIONS))
            donors = [section(d, path) for d in BUNDLED.values() if section(d, path) is not None]
            if donors:
                data = inserted(data, path, draw(st.sampled_from(donors)))
        elif action == "repeat":
            lists = [p for p in paths if isinstance(section(data, p), list)]
            if lists:
                path = draw(st.sampled_from(lists))
                entries = section(data, path)
                short = len(as_text(entries)) < 100  # 20,000 copies of a long one: GBs of TOML
                many = short and draw(st.booleans())
                value = (entries * 20_000)[:20_000] if many else entries * 2
                data = mutated(data, path, "replace", value)
        elif paths:
            data = mutated(data, draw(st.sampled_from(paths)), action, draw(ODD_VALUES))
    return name, tomli_w.dumps(data)


EVERY_ACTION = ("delete", "replace", "insert", "graft", "graft", "repeat")
"""The slow fuzz's actions (a graft twice as often: the tables it brings make mutants that run)."""

TEXTS = [
    "9" * 5000, "1e6", "1e300", "-1e300", "inf", "-inf", "nan", "0", "-0.0", "5e-324", "true",
    "vertical", '"x"', "", "[]", "[inf, 0.0]", "[nan, 1.0]", "[1e300, 1e300]",
    "[[0.0, 0.11], [0.0, 0.12], [0.01, 0.11]]", '["granules", "granules"]',
    '{ kind = "nope" }', "[" + "1.0, " * 2000 + "1.0]",
]  # fmt: skip
"""Values of ``--set`` as typed: long integers, non-finite and huge numbers, lists, tables."""


def as_text(value: Any) -> str:
    """``value`` as a ``--set`` value (TOML; a table inline)."""
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {as_text(v)}" for k, v in value.items()) + " }"
    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def dotted(path: tuple) -> str:
    """A key path as ``--set`` names it (``contacts[0].friction``)."""
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in path).lstrip(".")


@st.composite
def override_sets(draw: st.DrawFn) -> tuple[str, list[str]]:
    """(bundled case, one to three ``KEY=VALUE`` overrides of any key of the schema)."""
    name = draw(st.sampled_from(sorted(BUNDLED)))
    sets = []
    for _ in range(draw(st.integers(1, 3))):
        path, value = draw(key_and_value(BUNDLED[name]))
        text = draw(st.one_of(st.just(as_text(value)), st.sampled_from(TEXTS)))
        sets.append(f"{dotted(path)}={text}")
    return name, sets


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


GEOMETRY = '"../geometry/'
"""How the bundled cases name their geometry files (a mutant written elsewhere names them
absolutely)."""


def draw_each(strategy: st.SearchStrategy, n: int, seed_value: int, check: Any) -> None:
    """Call ``check`` on ``n`` examples of ``strategy`` (seeded, generated only: nothing to
    shrink, no example database)."""

    @seed(seed_value)
    @settings(max_examples=n, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(example=strategy)
    def each(example: Any) -> None:
        check(example)

    each()


def fuzz(folder: Path, cases: int, sets: int, seed_value: int) -> tuple[Counter, list[str], str]:
    """``cases`` mutants over every section and ``sets`` sets of overrides, each validated and,
    if accepted, run for a few steps by a worker (:class:`~tests.case.fuzz_worker.Worker`):
    the counts (mutants, refused, accepted, run, tracebacks, hangs; by kind; "peak MB", the
    worker's largest memory), what each traceback or hang was, and the job that took the most
    memory."""
    counts: Counter = Counter()
    failures: list[str] = []
    largest = [""]

    def count(kind: str, case: Path, overrides: list[str]) -> None:
        answer = worker(case, overrides, folder / "run")
        outcome = answer["outcome"]
        counts[kind] += 1
        counts[outcome] += 1
        if answer.get("peak_mb", 0) > counts["peak MB"]:
            counts["peak MB"] = answer["peak_mb"]
            largest[0] = f"{case.name} {[o[:80] for o in overrides]}: {answer['detail']}"
        if outcome in ("traceback", "hang"):
            failures.append(f"{outcome}: {case.name} {overrides}: {answer['detail']}")

    def case_file(mutant: tuple[str, str]) -> None:
        name, text = mutant
        path = folder / name
        path.write_text(text.replace(GEOMETRY, f'"{ROOT}/geometry/'), encoding="utf-8")
        count("mutants", path, [])

    def override(example: tuple[str, list[str]]) -> None:
        name, overrides = example
        count("override sets", ROOT / "cases" / name, overrides)

    with Worker() as worker:
        draw_each(mutants(EVERY_ACTION), cases, seed_value, case_file)
        draw_each(override_sets(), sets, seed_value, override)
    return counts, failures, largest[0]


@pytest.mark.slow
def test_mutants_over_every_section_and_overrides_are_refused_or_run(tmp_path):
    """2,000 mutants and 1,000 sets of overrides (seed 0): each refused, accepted as a parameter
    set, or run for a few steps; no traceback, no hang."""
    counts, failures, _ = fuzz(tmp_path, cases=2000, sets=1000, seed_value=0)
    assert counts["mutants"] >= 2000 and counts["override sets"] >= 1000, counts
    assert counts["ran"] > 0 and counts["refused"] > 0, counts
    assert not failures, "\n".join(failures[:20])
