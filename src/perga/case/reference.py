"""The case-file reference (docs/case-files.md), generated from the schema so it cannot drift."""

from __future__ import annotations

import json
import typing
from typing import Any

from pydantic import BaseModel

from perga.case.schema import Case

HEADER = """# Case files

Generated from `perga.case.schema` by `perga schema --markdown` (a test checks that this page is
current). SI units throughout. Unknown keys are errors with a "did you mean" hint; `perga validate
CASE...` checks the schema and the physical cross-checks (`perga.case.checks`) and lists every
problem. `perga schema` prints the JSON Schema.
"""


def _models(annotation: Any) -> list[type[BaseModel]]:
    """The schema models inside a field's annotation (through Optional, unions, lists, dicts)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found = []
    for arg in typing.get_args(annotation):
        found += _models(arg)
    return found


def _type_name(annotation: Any) -> str:
    text = str(annotation).replace("typing.", "").replace("perga.case.schema.", "")
    text = text.replace("<class '", "").replace("'>", "").replace("NoneType", "None")
    return text.replace(" | ", " or ")


def _table(model: type[BaseModel], prefix: str, seen: set[str]) -> list[str]:
    lines = [
        f"## `[{prefix}]`" if prefix else "## top level",
        "",
        (model.__doc__ or "").strip(),
        "",
    ]
    lines += ["| key | type | default | meaning |", "|---|---|---|---|"]
    nested = []
    for name, field in model.model_fields.items():
        default = (
            "required"
            if field.is_required()
            else (
                "(see table)"
                if field.default_factory
                else json.dumps(field.default, ensure_ascii=False)
            )
        )
        lines.append(
            f"| `{name}` | `{_type_name(field.annotation)}` | {default} | "
            f"{(field.description or '').replace('|', '/')} |"
        )
        for sub in _models(field.annotation):
            key = f"{prefix}.{name}" if prefix else name
            if (
                isinstance(typing.get_origin(field.annotation), type)
                and typing.get_origin(field.annotation) is dict
            ):
                key += ".NAME"
            if sub.__name__ + key not in seen:
                seen.add(sub.__name__ + key)
                nested.append((sub, key))
    lines.append("")
    for sub, key in nested:
        lines += _table(sub, key, seen)
    return lines


def markdown_reference() -> str:
    """Every table and key of a case file, with type, default, unit and range."""
    return HEADER + "\n" + "\n".join(_table(Case, "", set())).rstrip() + "\n"


def json_schema() -> str:
    """The JSON Schema of a case file."""
    return json.dumps(Case.model_json_schema(), indent=2, ensure_ascii=False)


__all__ = ["json_schema", "markdown_reference"]
