"""Read a case file (TOML) into a :class:`~perga.case.schema.Case`, collecting every problem.

Problems read ``cases/x.toml: hammers.mass: must be > 0 (got -0.01)``; unknown keys get a
"did you mean" hint. No traceback reaches the user for bad input: callers catch
:class:`CaseError`.
"""

from __future__ import annotations

import difflib
import tomllib
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from perga.case.checks import check_case
from perga.case.schema import Case


class CaseError(Exception):
    """A case file that cannot be used; ``problems`` lists every message, each naming the file."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("\n".join(problems))
        self.problems = problems


def _model_at(loc: tuple[Any, ...]) -> type[BaseModel] | None:
    """The schema model that owns the key at ``loc`` (for "did you mean" suggestions)."""
    model: Any = Case
    for part in loc[:-1]:
        if isinstance(part, int) or not (isinstance(model, type) and issubclass(model, BaseModel)):
            continue
        field = model.model_fields.get(part)
        if field is None:
            return None
        model = field.annotation
        args = getattr(model, "__args__", ())
        model = next((a for a in args if isinstance(a, type) and issubclass(a, BaseModel)), model)
    return model if isinstance(model, type) and issubclass(model, BaseModel) else None


def _describe(error: dict[str, Any]) -> str:
    loc = tuple(error["loc"])
    key = ".".join(str(p) if not isinstance(p, int) else f"[{p}]" for p in loc).replace(".[", "[")
    if error["type"] == "extra_forbidden":
        owner = _model_at(loc)
        options = list(owner.model_fields) if owner else []
        close = difflib.get_close_matches(str(loc[-1]), options, n=1)
        hint = f"; did you mean '{close[0]}'?" if close else f"; allowed: {', '.join(options)}"
        return f"{key}: unknown key{hint}"
    message = error["msg"].removeprefix("Value error, ")
    got = f" (got {error['input']!r})" if "input" in error and error["type"] != "missing" else ""
    owner = _model_at(loc)
    field = owner.model_fields.get(str(loc[-1])) if owner and loc else None
    expected = f" [{field.description}]" if field and field.description else ""
    return f"{key or '(top level)'}: {message}{got}{expected}"


def load_case(path: str | Path, source_dir: Path | None = None) -> Case:
    """Parse and validate a case file; raises :class:`CaseError` listing every problem.

    Relative geometry paths start at ``source_dir`` (default: the case file's folder; a run
    directory's copy of a case passes its original folder). The schema's problems are all
    reported at once; the physical cross-checks
    (:mod:`perga.case.checks`) need valid fields, so they run, all of them, once the schema passes.
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise CaseError([f"{path}: cannot read ({exc.strerror})"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{path}: not valid TOML: {exc}"]) from None
    try:
        case = Case.model_validate(data)
    except ValidationError as exc:
        raise CaseError([f"{path}: {_describe(err)}" for err in exc.errors()]) from None
    case._source_dir = source_dir or path.resolve().parent
    problems = check_case(case)
    if problems:
        raise CaseError([f"{path}: {problem}" for problem in problems])
    return case
