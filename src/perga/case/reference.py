"""The case-file reference (docs/reference/case-files.md), generated from the schema so it
cannot drift, and the units of a case file's keys as the schema's descriptions give them."""

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

from perga.case.schema import Case, ContactKind, _mentions_number

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

PAGE = Path("docs") / "reference" / "case-files.md"
"""Where the page lives in the source tree."""

HEADER = f"""# Case files

Generated from `perga.case.schema`: `perga schema --markdown > {PAGE.as_posix()}` rewrites it (a
test fails when it is out of date). SI units throughout; a key's unit is `-` for a dimensionless
number. Unknown keys are errors with a "did you mean" hint; `perga validate CASE...` checks the
schema and the physical cross-checks (`perga.model.checks`) and lists every problem. `perga
schema` prints the JSON Schema.
"""

_SYMBOL = r"(?:kg|m|s|rad|N|Pa|J)[²³]?"
_UNIT = rf"{_SYMBOL}(?:[·/](?:{_SYMBOL}|\({_SYMBOL}(?:·{_SYMBOL})*\)))*|rev/min"
_UNIT_END = r"(?=$|[,;:]| \(| after\b| from\b| by\b)"
_UNIT_IN_TEXT = re.compile(
    rf"(?:^|, |: |, or )(?P<unit>{_UNIT}){_UNIT_END}|\bper (?P<per>{_UNIT}){_UNIT_END}"
)
"""A unit in a field's description: a segment of its own ("angular velocity, rad/s, in ..."),
or after "per" (a rate: 1/s)."""
DIMENSIONLESS = "-"
"""The unit of a dimensionless number."""


def field_unit(model: type[BaseModel], name: str) -> tuple[str, ...]:
    """The SI units of key ``name`` of table ``model`` as its description states them
    (``("N/m", "Pa")`` where the unit depends on the contact law, ``("1/s", "kg/s")`` for a rate
    by number or by mass), or, for a field without a description, as the table's docstring
    does ("``centre`` (m)"); ``("-",)`` for a dimensionless number, ``()`` for a key that is no
    number (text, a name, a choice, a table)."""
    field = model.model_fields[name]
    if not _mentions_number(field.annotation):
        return ()
    text = field.description
    if text is None:
        own = re.search(rf"``{name}`` \((?P<unit>{_UNIT})\)", model.__doc__ or "")
        return (own["unit"],) if own else (DIMENSIONLESS,)
    units = [m["unit"] or f"1/{m['per']}" for m in _UNIT_IN_TEXT.finditer(text)]
    return tuple(dict.fromkeys(units)) or (DIMENSIONLESS,)


def tables_of(annotation: Any) -> list[type[BaseModel]]:
    """The schema models inside a field's annotation (through Optional, unions, lists, dicts)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    found = []
    for arg in typing.get_args(annotation):
        found += tables_of(arg)
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
        words = dict.fromkeys(_type_name(a) for a in args if a is not type(None))
        return " or ".join(words) + (" (optional)" if type(None) in args else "")
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


def choices(field: FieldInfo) -> tuple[str, ...]:
    """The values a choice key takes: its Literal's, or for a kind read from a registry
    (:class:`~perga.case.schema.ContactKind`) its current choices; () for any other key."""
    for kind in field.metadata:
        if isinstance(kind, ContactKind):
            return kind.choices()
    return _literal_values(field.annotation)


def _literal_values(annotation: Any) -> tuple[str, ...]:
    """The values of the Literals in ``annotation`` (through Optional, unions and lists)."""
    if typing.get_origin(annotation) is typing.Literal:
        return typing.get_args(annotation)
    return tuple(v for a in typing.get_args(annotation) for v in _literal_values(a))


def _field_type(field: FieldInfo) -> str:
    """A field's type in words (:func:`_type_name`); a kind read from a registry as the Literal
    of its current choices."""
    kinds = choices(field)
    if kinds and not _literal_values(field.annotation):
        return _type_name(typing.Literal[kinds])
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
    if item.startswith("one of "):
        return "list of " + item.removeprefix("one of ")
    return f"list of {item}s" if item in ("number", "integer", "table") else f"list of {item}"


def _example(key: str, model: type[BaseModel]) -> str:
    """``[key]`` (of ``model``'s kind, if it has one) as the first bundled case that has it
    writes it, in Markdown ("" if none does)."""
    kind = _own_kind(model)
    for path in EXAMPLE_CASES:
        snippet = _snippet((CASES / path).read_text(encoding="utf-8"), key)
        if snippet and (kind is None or f'kind = "{kind}"' in snippet):
            return f"Example, from `cases/{path}`:\n\n```toml\n{snippet}\n```"
    return ""


def _own_kind(model: type[BaseModel]) -> str | None:
    """The one value ``model``'s ``kind`` takes (a form of a table that has several), or None."""
    field = model.model_fields.get("kind")
    kinds = typing.get_args(field.annotation) if field else ()
    return kinds[0] if len(kinds) == 1 else None


_OWN_NAME = re.compile(r'^\[\[?[\w.]+\]\]?(?: with)?(?: kind = "\w+")?(?::\s+|\.\s*$)')
"""A docstring's opening that names its table (the page's heading names it)."""
_ROLE = re.compile(r":\w+:`~?([^`]+)`")
_DOUBLE_BACKTICKS = re.compile(r"``([^`]+)``")


def rst_to_markdown(text: str) -> str:
    """A docstring's reStructuredText literals and cross-references as Markdown code."""
    return _DOUBLE_BACKTICKS.sub(r"`\1`", _ROLE.sub(r"`\1`", text))


def _prose(model: type[BaseModel]) -> str:
    """A table's docstring as Markdown, without the opening that names the table."""
    text = rst_to_markdown(_OWN_NAME.sub("", inspect.cleandoc(model.__doc__ or "")))
    return text[:1].upper() + text[1:]


def table_cell(text: str) -> str:
    """``text`` (reStructuredText or plain) in a Markdown table cell: on one line, its pipes
    escaped."""
    return " ".join(rst_to_markdown(text).split()).replace("|", "\\|")


def _heading(model: type[BaseModel], key: str, listed: bool) -> str:
    """The section heading of table ``key`` (an array of tables if ``listed``), with the kind
    of the form it shows."""
    if not key:
        return "## Top level"
    kind = _own_kind(model)
    name = f"[[{key}]]" if listed else f"[{key}]"
    return f"## `{name}`" + (f' with `kind = "{kind}"`' if kind else "")


def _default(field: FieldInfo) -> str:
    if field.is_required():
        return "required"
    if field.default_factory:
        return "(see table)"
    return json.dumps(field.default, ensure_ascii=False)


def _table(model: type[BaseModel], key: str, listed: bool, seen: set[str]) -> list[str]:
    """The section of table ``key`` and those of the tables inside it, as Markdown blocks."""
    example = _example(key, model) if key else ""
    blocks = [b for b in (_heading(model, key, listed), _prose(model), example) if b]
    rows = ["| key | type | unit | default | meaning |", "|---|---|---|---|---|"]
    nested = []
    for name, field in model.model_fields.items():
        unit = ", ".join(field_unit(model, name))
        rows.append(
            f"| `{name}` | `{_field_type(field)}` | {unit} | {table_cell(_default(field))} | "
            f"{table_cell(field.description or '')} |"
        )
        origin = typing.get_origin(field.annotation)
        sub_key = f"{key}.{name}" if key else name
        sub_key += ".NAME" if origin is dict else ""
        for sub in tables_of(field.annotation):
            if sub.__name__ + sub_key not in seen:
                seen.add(sub.__name__ + sub_key)
                nested.append((sub, sub_key, origin is list))
    if model.model_fields:
        blocks.append("\n".join(rows))
    for sub, sub_key, sub_listed in nested:
        blocks += _table(sub, sub_key, sub_listed, seen)
    return blocks


def markdown_reference() -> str:
    """Every table and key of a case file, with type, default, unit and range; a complete
    case at the top and an example of each table from the bundled cases."""
    whole = (CASES / ANNOTATED).read_text(encoding="utf-8").rstrip()
    top = f"A complete case, `cases/{ANNOTATED}`:\n\n```toml\n{whole}\n```"
    return "\n\n".join([HEADER.rstrip(), top, *_table(Case, "", False, set())]) + "\n"


def json_schema() -> str:
    """The JSON Schema of a case file."""
    return json.dumps(Case.model_json_schema(), indent=2, ensure_ascii=False)


__all__ = [
    "choices",
    "field_unit",
    "json_schema",
    "markdown_reference",
    "rst_to_markdown",
    "table_cell",
    "tables_of",
]
