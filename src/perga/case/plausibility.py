"""Material values a case accepts but no granular material or machine part has: warnings, not
refusals (a user may mean them), each naming the unit the value probably was typed in.

Ranges (SI): density 100-25,000 kg/m³ (from light agricultural granules, bran or chaff
about 100-300, to tungsten carbide, 15,600; osmium, the densest element, 22,600); Young's modulus
1e6-1.2e12 Pa (soft rubber, about 1e6, to diamond, 1.05e12; a hydrogel bead, softer, is
warned about too)."""

from __future__ import annotations

from perga.case.schema import Case

DENSITY = (100.0, 25_000.0)
"""kg/m³: the densities of real granules and machine parts (module doc)."""
MODULUS = (1e6, 1.2e12)
"""Pa: the Young's moduli of real granules and machine parts (module doc)."""

_DENSITY_UNITS = (("g/cm³", 1e3),)
_MODULUS_UNITS = (("GPa", 1e9), ("MPa", 1e6), ("kPa", 1e3))


def _meant(
    value: float, units: tuple[tuple[str, float], ...], span: tuple[float, float], si: str
) -> str:
    """ "; typed in UNIT? ..." for the first of ``units`` (name, its size in ``si``) that puts
    ``value`` in ``span``, else ""."""
    for name, factor in units:
        if span[0] <= value * factor <= span[1]:
            return f"; typed in {name}? {value:g} {name} is {value * factor:g} {si}"
    return ""


def implausible(case: Case) -> list[str]:
    """A warning for each material value of ``case`` outside the range of real materials
    (:data:`DENSITY`, :data:`MODULUS`), as "key: message"."""
    warnings = []
    for name, material in case.materials.items():
        density = material.density
        if not DENSITY[0] <= density <= DENSITY[1]:
            warnings.append(
                f"materials.{name}.density = {density:g} kg/m³ is outside the densities of "
                f"real granules and machine parts ({DENSITY[0]:g}-{DENSITY[1]:g} kg/m³)"
                + _meant(density, _DENSITY_UNITS, DENSITY, "kg/m³")
            )
        modulus = material.youngs_modulus
        if modulus is not None and not MODULUS[0] <= modulus <= MODULUS[1]:
            warnings.append(
                f"materials.{name}.youngs_modulus = {modulus:g} Pa is outside the moduli of real "
                f"granules and machine parts ({MODULUS[0]:g}-{MODULUS[1]:g} Pa)"
                + _meant(modulus, _MODULUS_UNITS, MODULUS, "Pa")
            )
    return warnings
