"""Overrides of a case file's keys: ``KEY=VALUE`` with a dotted key, applied to the file's TOML
data before validation, so that an overridden case is checked exactly like a file.

Keys follow the file: ``rotor.rpm``, ``hammers.mass``, ``materials.beebread.density``,
``effects.air_drag.drag_coefficient`` (missing tables are created). Lists of tables are indexed
``[i]`` (``contacts[0].restitution``, ``granules.placement.positions[2]``), and ``[[contacts]]``
also by its pair, named by materials or by role in either order: ``contacts.beebread-steel``,
``contacts.granule-hammer``, ``contacts.granule-granule``, ``contacts.granule-chamber``
(roles: ``granule``, ``hammer``, ``chamber`` = the materials of ``granules``, ``hammers`` and
``chamber``). Values are TOML values (``2400``, ``0.65``, ``"vertical"``, ``[0.1, 0.2]``,
``true``); a value that is not TOML is taken as a string (``rotor.plane=vertical``).
"""

from __future__ import annotations

import copy
import re
import sys
import tomllib
from collections.abc import Iterable
from typing import Any

from perga.case.schema import Case

ROLES = {"granule": "granules", "hammer": "hammers", "chamber": "chamber"}
"""Contact roles -> the table whose ``material`` they name."""

EXAMPLE = "e.g. hammers.mass, contacts[0].friction, contacts.granule-hammer.restitution"
_SEGMENT = re.compile(r"([^.\[\]]+)|\[(-?\d+)\]")


class OverrideError(ValueError):
    """An override that cannot be applied; the message names the override and what is allowed,
    ``parts`` the parts of the key it sets (:func:`key_parts`) where the problem is its value."""

    def __init__(self, message: str, parts: tuple[str | int, ...] = ()) -> None:
        super().__init__(message)
        self.parts = parts


class NumberTooLong(tomllib.TOMLDecodeError):
    """TOML with an integer of more digits than Python reads (``sys.get_int_max_str_digits()``),
    far beyond the range of every key."""


def parse_toml(text: str) -> dict[str, Any]:
    """The TOML ``text`` as tomllib reads it; an integer too long to read is
    :class:`NumberTooLong` naming its line (tomllib lets Python's ValueError through)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError:
        raise
    except ValueError:
        limit = sys.get_int_max_str_digits()
        number = re.search(rf"\d[\d_]{{{limit},}}", text)
        where = f" (line {text.count(chr(10), 0, number.start()) + 1})" if number else ""
        raise NumberTooLong(
            f"an integer of more than {limit} digits{where}, beyond the range of every key"
        ) from None


def parse_value(text: str) -> Any:
    """A TOML value, or the text itself when it is not one (:class:`NumberTooLong` for an
    integer too long to read)."""
    try:
        return parse_toml(f"v = {text}")["v"]
    except NumberTooLong:
        raise
    except tomllib.TOMLDecodeError:
        return text


def split_override(text: str) -> tuple[str, Any]:
    """``KEY=VALUE`` -> (key, parsed value)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise OverrideError(f"--set {text!r}: expected KEY=VALUE, e.g. rotor.rpm=2400")
    key = key.strip()
    try:
        return key, parse_value(value.strip())
    except NumberTooLong as exc:
        message = f"--set {key}: {exc}".replace(" (line 1)", "")
        raise OverrideError(message, tuple(key_parts(key))) from None


def key_parts(key: str) -> list[str | int]:
    """A dotted key's parts: table keys, and list indices as ints."""
    parts: list[str | int] = []
    pos = 0
    for match in _SEGMENT.finditer(key):
        if match.start() != pos and key[pos : match.start()] != ".":
            raise OverrideError(f"--set {key}: not a dotted key ({EXAMPLE})")
        parts.append(match.group(1) if match.group(1) is not None else int(match.group(2)))
        pos = match.end()
    if pos != len(key) or not parts:
        raise OverrideError(f"--set {key}: not a dotted key ({EXAMPLE})")
    return parts


def _material(data: dict[str, Any], name: str) -> str:
    """A contact's end: a role's material (the schema's default where the table names none),
    or the name itself."""
    if name not in ROLES:
        return name
    table = data.get(ROLES[name])
    if isinstance(table, dict) and isinstance(table.get("material"), str):
        return table["material"]
    model = Case.model_fields[ROLES[name]].annotation
    model = next(a for a in getattr(model, "__args__", (model,)) if hasattr(a, "model_fields"))
    return str(model.model_fields["material"].default)


def _contact_index(data: dict[str, Any], label: str, key: str) -> int:
    """The [[contacts]] entry of the pair ``label`` ("a-b", materials or roles)."""
    contacts = data.get("contacts")
    if not isinstance(contacts, list):
        raise OverrideError(f"--set {key}: the case has no [[contacts]]")
    ends = label.split("-")
    pairs = [c.get("pair") for c in contacts if isinstance(c, dict)]
    names = ", ".join("-".join(p) for p in pairs if isinstance(p, list))
    if len(ends) != 2:
        raise OverrideError(
            f"--set {key}: a contact pair is named 'a-b' by materials or roles "
            f"(granule, hammer, chamber); pairs in the case: {names}"
        )
    wanted = sorted(_material(data, e) for e in ends)
    for index, pair in enumerate(pairs):
        if isinstance(pair, list) and sorted(pair) == wanted:
            return index
    raise OverrideError(
        f"--set {key}: no [[contacts]] entry for the pair {wanted[0]}-{wanted[1]}; "
        f"pairs in the case: {names}"
    )


def apply_overrides(data: dict[str, Any], overrides: Iterable[tuple[str, Any]]) -> dict[str, Any]:
    """A copy of the TOML ``data`` with each (key, value) set (module doc for the keys)."""
    out = copy.deepcopy(data)
    for key, value in overrides:
        parts = key_parts(key)
        if parts[0] == "contacts" and len(parts) > 1 and isinstance(parts[1], str):
            parts[1] = _contact_index(out, parts[1], key)
        node: Any = out
        for i, part in enumerate(parts[:-1]):
            node = _step(node, part, parts[i + 1], key)
        last = parts[-1]
        if isinstance(last, int):
            _check_index(node, last, key)
        elif not isinstance(node, dict):
            raise OverrideError(f"--set {key}: {_path(parts[:-1])} is not a table")
        node[last] = value
    return out


def _path(parts: list[str | int]) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in parts).lstrip(".")


def _check_index(node: Any, index: int, key: str) -> None:
    if not isinstance(node, list):
        raise OverrideError(f"--set {key}: [{index}] indexes something that is not a list")
    if not -len(node) <= index < len(node):
        raise OverrideError(f"--set {key}: index {index} out of range (the list has {len(node)})")


def _step(node: Any, part: str | int, following: str | int, key: str) -> Any:
    """The child ``part`` of ``node``, created as a table when missing."""
    if isinstance(part, int):
        _check_index(node, part, key)
        return node[part]
    if not isinstance(node, dict):
        raise OverrideError(f"--set {key}: cannot set a key inside a value that is not a table")
    if part not in node:
        if isinstance(following, int):
            raise OverrideError(f"--set {key}: {part} is not in the case: no [{following}] in it")
        node[part] = {}
    return node[part]
