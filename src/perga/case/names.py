"""The names a case uses: every material it names is defined, and every pair of materials
its scene brings into contact has a [[contacts]] entry. Checked with the schema by
:func:`perga.case.load.load_case` (the physical cross-checks need the names:
:mod:`perga.model.checks`). And the hint for an unknown key (:func:`unknown_key`)."""

from __future__ import annotations

import difflib
from collections.abc import Sequence

from perga.case.schema import Case

MEANT = {
    "speed": ("rpm", "omega"),
    "rotation": ("rpm", "omega"),
    "angular_velocity": ("omega", "rpm"),
    "rev": ("rpm",),
    "revs": ("rpm",),
    "diameter": ("radius",),
    "weight": ("mass",),
    "e": ("restitution",),
    "mu": ("friction",),
    "time": ("duration",),
    "step": ("dt",),
    "timestep": ("dt",),
}
"""Words users type for a quantity whose key has another name -> the keys they probably mean
(offered where the table has them; a spelling's nearest key can be a different quantity:
``speed`` is spelled like ``shape``)."""


def unknown_key(name: str, options: Sequence[str]) -> str:
    """The message for an unknown key ``name`` among ``options``: the keys its meaning or its
    spelling suggests, or the allowed keys."""
    meant = [k for k in MEANT.get(name.lower(), ()) if k in options]
    close = meant or difflib.get_close_matches(name, list(options), n=1)
    if close:
        return "unknown key; did you mean " + " or ".join(f"'{k}'" for k in close) + "?"
    return f"unknown key; allowed: {', '.join(options)}"


def name_problems(case: Case) -> list[str]:
    """The problems of the names ``case`` uses, as "key: message" strings."""
    names = set(case.materials)
    used = [
        ("hammers.material", case.hammers.material),
        ("granules.material", case.granules.material),
    ]
    if case.chamber:
        used.append(("chamber.material", case.chamber.material))
    used += [(f"contacts[{i}].pair", n) for i, c in enumerate(case.contacts) for n in c.pair]
    problems = [
        f"{key}: unknown material {name!r} (defined: {', '.join(sorted(names))})"
        for key, name in used
        if name not in names
    ]
    problems += _repeated_pairs(case)
    if problems:
        return problems
    needed = [(case.granules.material, case.hammers.material)]
    if case.chamber:
        needed.append((case.granules.material, case.chamber.material))
    if case.effects.granule_collisions:
        needed.append((case.granules.material, case.granules.material))
    for a, b in needed:
        try:
            case.contact(a, b)
        except KeyError:
            problems.append(
                f"contacts: no entry for the pair [{a!r}, {b!r}], which this scene uses"
            )
    return problems


def _repeated_pairs(case: Case) -> list[str]:
    """A [[contacts]] entry for a pair of materials that an entry before it already has."""
    first: dict[tuple[str, ...], int] = {}
    problems = []
    for i, contact in enumerate(case.contacts):
        pair = tuple(sorted(contact.pair))
        if pair in first:
            problems.append(
                f"contacts[{i}].pair: {list(contact.pair)} is given again (first in "
                f"contacts[{first[pair]}]): one entry per pair of materials"
            )
        first.setdefault(pair, i)
    return problems
