"""Read a case file (TOML) into a :class:`~perga.case.schema.Case`, collecting every problem.

Problems read ``cases/x.toml: hammers.mass: must be > 0 (got -0.01)``; unknown keys get a
"did you mean" hint. No traceback reaches the user for bad input: callers catch
:class:`CaseError`.
"""

from __future__ import annotations

import reprlib
import tomllib
import typing
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from perga.case.names import name_problems, unknown_key
from perga.case.overrides import (
    OverrideError,
    apply_overrides,
    parse_toml,
    split_override,
)
from perga.case.schema import NOT_A_NUMBER, Case

SHOWN = reprlib.Repr()
"""How a problem quotes a value: long strings, numbers, lists and tables cut short."""
SHOWN.maxstring = SHOWN.maxother = 80
SHOWN.maxlist = SHOWN.maxtuple = 8
SHOWN.maxdict = 12
LONGEST_OVERRIDE = 100
MOST_PROBLEMS = 20
"""Problems of one file listed; the rest are counted."""
"""Characters of an override a problem quotes before it cuts it short."""


class CaseError(Exception):
    """A case file that cannot be used; ``problems`` lists every message, each naming the file."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("\n".join(problems))
        self.problems = problems


def _models(annotation: Any) -> list[type[BaseModel]]:
    """The schema models an annotation can hold (one, or a union's members)."""
    args = typing.get_args(annotation) or (annotation,)
    out = []
    for arg in args:
        out += _models(arg) if typing.get_args(arg) else []
        if isinstance(arg, type) and issubclass(arg, BaseModel):
            out.append(arg)
    return out


def _kind(model: type[BaseModel]) -> str | None:
    field = model.model_fields.get("kind")
    values = typing.get_args(field.annotation) if field else ()
    return str(values[0]) if len(values) == 1 else None


def _resolve(loc: tuple[Any, ...]) -> tuple[tuple[Any, ...], type[BaseModel] | None]:
    """``loc`` without the tags pydantic adds for a union member (``placement.shot.angle`` ->
    ``placement.angle``), and the model that owns its last key."""
    models: list[type[BaseModel]] = [Case]
    clean: list[Any] = []
    named = False  # the part before was a table of named entries ([materials.NAME])
    for i, part in enumerate(loc):
        if isinstance(part, int) or named:
            clean.append(part)
            named = False
            continue
        tagged = [m for m in models if _kind(m) == part]
        if tagged and len(models) > 1:
            models = tagged  # the member pydantic names by its kind: not a key of the file
            continue
        clean.append(part)
        if i == len(loc) - 1:
            break
        owner = next((m for m in models if part in m.model_fields), None)
        if owner is None:
            return tuple(clean), None
        annotation = owner.model_fields[part].annotation
        named = typing.get_origin(annotation) is dict
        models = _models(annotation)
    owner = next((m for m in models if loc and str(loc[-1]) in m.model_fields), None)
    if owner is None and len(models) == 1:
        owner = models[0]
    return tuple(clean), owner


def _describe(error: dict[str, Any]) -> str:
    """A schema error as "key: message" (the key dotted, ``[i]`` for an index)."""
    if error["type"] == NOT_A_NUMBER:  # raised for its table: the key and value are in ctx
        ctx = error["ctx"]
        error = error | {"loc": (*error["loc"], ctx["field"]), "input": ctx["value"]}
    loc, owner = _resolve(tuple(error["loc"]))
    key = ".".join(str(p) if not isinstance(p, int) else f"[{p}]" for p in loc).replace(".[", "[")
    if error["type"] == "extra_forbidden":
        options = list(owner.model_fields) if owner else []
        return f"{key}: {unknown_key(str(loc[-1]), options)}"
    message = error["msg"].removeprefix("Value error, ")
    shown = "input" in error and error["type"] != "missing"
    got = f" (got {SHOWN.repr(error['input'])})" if shown else ""
    return f"{key or '(top level)'}: {message}{got}{_expected(tuple(error['loc']))}"


def _expected(loc: tuple[Any, ...]) -> str:
    """The description of the field at ``loc`` (its unit and range; for an item of a list, the
    list's) as a problem ends with it, in brackets, or ""."""
    while loc and isinstance(loc[-1], int):
        loc = loc[:-1]
    _, owner = _resolve(loc)
    field = owner.model_fields.get(str(loc[-1])) if owner and loc else None
    return f" [{field.description}]" if field and field.description else ""


def _blamed(
    problems: list[str],
    data: dict[str, Any],
    path: Path,
    source_dir: Path | None,
    overrides: Sequence[str],
) -> list[str]:
    """``problems`` of the case with ``overrides``, each one the file alone does not have
    (``data``, validated again) named by the override that set its key (or a table above it),
    or by all of them."""
    try:
        validate_case(data, path, source_dir)
        own: set[str] = set()
    except CaseError as exc:
        own = set(exc.problems)
    blamed = []
    for problem in problems:
        line = problem.removeprefix(f"{path}: ")
        if problem in own or line == problem:
            blamed.append(problem)
            continue
        key = line.split(":", 1)[0]
        named = [
            o
            for o in overrides
            if key == (name := split_override(o)[0]) or key.startswith((f"{name}.", f"{name}["))
        ]
        sets = ", ".join(f"--set {_shortened(o)}" for o in named or overrides)
        blamed.append(f"{path} with {sets}: {line}")
    return blamed


def _shortened(override: str) -> str:
    """``override`` as a problem quotes it: cut short after ``LONGEST_OVERRIDE`` characters."""
    if len(override) <= LONGEST_OVERRIDE:
        return override
    return f"{override[:LONGEST_OVERRIDE]}... ({len(override)} characters)"


def read_case_data(path: str | Path) -> dict[str, Any]:
    """The TOML data of a case file (:class:`CaseError` naming the file if it cannot be read)."""
    path = Path(path)
    try:
        return parse_toml(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise CaseError([f"{path}: cannot read ({exc.strerror})"]) from None
    except UnicodeDecodeError:
        raise CaseError([f"{path}: not a text file (TOML must be UTF-8)"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{path}: not valid TOML: {exc}"]) from None


def overridden(data: dict[str, Any], overrides: Sequence[str], path: str | Path) -> dict[str, Any]:
    """``data`` with the ``KEY=VALUE`` overrides applied (:mod:`perga.case.overrides`);
    :class:`CaseError` naming the file and the override if one cannot be applied."""
    try:
        return apply_overrides(data, [split_override(o) for o in overrides])
    except OverrideError as exc:
        raise CaseError([f"{path}: {exc}{_expected(exc.parts)}"]) from None


def validate_case(data: dict[str, Any], path: str | Path, source_dir: Path | None = None) -> Case:
    """Validate a case's TOML data; problems name ``path``. Raises :class:`CaseError` listing
    every problem: the schema's all at once, then (they need valid fields) the names'
    (:mod:`perga.case.names`). The physical cross-checks run when the case is compiled into
    a system (:func:`perga.model.compile.compile_case`)."""
    path = Path(path)
    try:
        case = Case.model_validate(data)
    except ValidationError as exc:
        raise CaseError(_listed(path, [_describe(err) for err in exc.errors()])) from None
    case.attach_source(source_dir or path.resolve().parent, data, path=path)
    problems = name_problems(case)
    if problems:
        raise CaseError(_listed(path, problems))
    return case


def _listed(path: Path, problems: list[str]) -> list[str]:
    """The first ``MOST_PROBLEMS`` problems, each naming ``path``, and how many more."""
    listed = [f"{path}: {problem}" for problem in problems[:MOST_PROBLEMS]]
    more = len(problems) - MOST_PROBLEMS
    return listed + [f"{path}: ... and {more} more problems"] * (more > 0)


def load_case(
    path: str | Path, source_dir: Path | None = None, overrides: Sequence[str] = ()
) -> Case:
    """Parse and validate a case file (its schema and names, :func:`validate_case`), with
    ``KEY=VALUE`` ``overrides`` applied first (checked exactly like the file); raises
    :class:`CaseError` listing every problem.

    Relative geometry paths start at ``source_dir`` (default: the case file's folder; a run
    directory's copy of a case passes its original folder).
    """
    path = Path(path)
    data = read_case_data(path)
    changed = overridden(data, overrides, path) if overrides else data
    try:
        case = validate_case(changed, path, source_dir)
    except CaseError as exc:
        if not overrides:
            raise
        raise CaseError(_blamed(exc.problems, data, path, source_dir, overrides)) from None
    case.attach_source(case.source_dir, changed, tuple(overrides), path=path)
    return case
