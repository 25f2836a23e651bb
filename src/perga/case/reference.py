"""The case-file reference (docs/case-files.md), generated from the schema so it cannot drift."""

from __future__ import annotations

import inspect
import json
import re
import types
import typing
from pathlib import Path
from typing import Any

from pydantic import BaseModel
from pydantic.fields import FieldInfo

from perga.case.schema import Case, ContactKind

CASES = Path(__file__).resolve().parents[3] / "cases"
EXAMPLE_CASES = (
    "separator.toml",
    "bee-bread-separator.toml",
    "soft-separator.toml",
    "vertical-rotor.toml",
    "plate-hammers-soft.toml",
    "single-granule.toml",
)
"""The bundled cases the examples come from, in order of preference."""
ANNOTATED = "soft-single-granule.toml"
"""The complete case shown at the top of the page."""

HEADER = """# Case files

Generated from `perga.case.schema` by `perga schema --markdown` (a test checks that this page is
current). SI units throughout. Unknown keys are errors with a "did you mean" hint; `perga validate
CASE...` checks the schema and the physical cross-checks (`perga.model.checks`) and lists every
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


_WORDS = {float: "number", int: "integer", str: "text", bool: "true or false", Any: "any"}


def _type_name(annotation: Any) -> str:
    """A field's type in words: "number", "one of 'a', 'b'", "list of tables", "integer or
    'auto'", "(optional)" where none is allowed."""
    if annotation in _WORDS:
        return _WORDS[annotation]
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return "table"
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is typing.Annotated:
        return _type_name(args[0])
    if origin is typing.Literal:
        values = [f"'{a}'" if isinstance(a, str) else str(a) for a in args]
        return values[0] if len(values) == 1 else "one of " + ", ".join(values)
    if origin in (typing.Union, types.UnionType):
        words = " or ".join(_type_name(a) for a in args if a is not type(None))
        return words + (" (optional)" if type(None) in args else "")
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return _list_of(args[0])
        if len(set(args)) == 1:
            return f"{len(args)} {_type_name(args[0])}s"
        return "(" + ", ".join(_type_name(a) for a in args) + ")"
    if origin is list:
        return _list_of(args[0])
    if origin is dict:
        return "tables by name"
    return str(annotation).replace("typing.", "")


def _field_type(field: FieldInfo) -> str:
    """A field's type in words (:func:`_type_name`); a kind read from a registry
    (:class:`~perga.case.schema.ContactKind`) as the Literal of its current choices."""
    for kind in field.metadata:
        if isinstance(kind, ContactKind):
            return _type_name(typing.Literal[kind.choices()])
    return _type_name(field.annotation)


def _snippet(text: str, key: str) -> str:
    """The lines of TOML ``text`` that set table ``key`` (NAME: any name): its own ``[key]``
    block, or the line that sets it inline under its parent's header; "" if none."""
    pattern = re.escape(key).replace("NAME", r"[\w-]+")
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if re.fullmatch(rf"\[\[?{pattern}\]\]?", line.strip()):
            block = [line]
            for rest in lines[i + 1 :]:
                if rest.startswith("[") or (not rest.strip() and block[-1].strip() == ""):
                    break
                block.append(rest)
            return "\n".join(block).rstrip()
    parent, _, last = key.rpartition(".")
    if parent:
        head = _snippet(text, parent).splitlines()[:1]
        body = [x for x in _snippet(text, parent).splitlines() if x.startswith(f"{last} = ")]
        if head and body:
            return "\n".join(head + body)
    return ""


def _list_of(annotation: Any) -> str:
    item = _type_name(annotation)
    return f"list of {item}s" if item in ("number", "integer", "table") else f"list of {item}"


def _example(key: str, model: type[BaseModel]) -> str:
    """``[key]`` (of ``model``'s kind, if it has one) as the first bundled case that has it
    writes it ("" if none does)."""
    kind = model.model_fields.get("kind")
    kinds = typing.get_args(kind.annotation) if kind else ()
    for path in EXAMPLE_CASES:
        snippet = _snippet((CASES / path).read_text(encoding="utf-8"), key)
        if snippet and (len(kinds) != 1 or f'kind = "{kinds[0]}"' in snippet):
            return f"Example, from `cases/{path}`:\n\n```toml\n{snippet}\n```\n"
    return ""


def _table(model: type[BaseModel], prefix: str, seen: set[str]) -> list[str]:
    lines = [
        f"## `[{prefix}]`" if prefix else "## top level",
        "",
        inspect.cleandoc(model.__doc__ or ""),
        "",
    ]
    if prefix:
        lines.append(_example(prefix, model))
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
            f"| `{name}` | `{_field_type(field)}` | {default} | "
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
    """Every table and key of a case file, with type, default, unit and range; a complete
    case at the top and an example of each table from the bundled cases."""
    whole = (CASES / ANNOTATED).read_text(encoding="utf-8").rstrip()
    top = f"A complete case, `cases/{ANNOTATED}`:\n\n```toml\n{whole}\n```\n"
    return HEADER + "\n" + top + "\n" + "\n".join(_table(Case, "", set())).rstrip() + "\n"


def json_schema() -> str:
    """The JSON Schema of a case file."""
    return json.dumps(Case.model_json_schema(), indent=2, ensure_ascii=False)


__all__ = ["json_schema", "markdown_reference"]
