"""The names a case uses: every material it names is defined, and every pair of materials
its scene brings into contact has a [[contacts]] entry. Checked with the schema by
:func:`perga.case.load.load_case` (the physical cross-checks need the names:
:mod:`perga.model.checks`)."""

from __future__ import annotations

from perga.case.schema import Case


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
