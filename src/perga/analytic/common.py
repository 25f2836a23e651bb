"""Constants and small helpers shared by the analytical models (SI units)."""

import math

STANDARD_GRAVITY = 9.80665
"""Standard acceleration of gravity g0, m/s² (CGPM 1901)."""


def reduced_mass(m1: float, m2: float) -> float:
    """Reduced mass m1·m2/(m1 + m2), kg; either mass may be ``math.inf`` (a body that cannot move).

    Raises ValueError when both are infinite (no finite body to move).
    """
    if m1 <= 0 or m2 <= 0:
        raise ValueError(f"masses must be > 0 kg (got {m1}, {m2})")
    if math.isinf(m1) and math.isinf(m2):
        raise ValueError("reduced mass of two infinite masses is undefined")
    if math.isinf(m1):
        return m2
    if math.isinf(m2):
        return m1
    return m1 * m2 / (m1 + m2)
