"""Hertz's law with Tsuji's damping, F = k_n√R* δ^{3/2} + α√(k_n√R* m_eff) δ^{1/4} δ̇ (Tsuji et
al., Powder Technol. 71 (1992) 239), k_n = (4/3)E* in Pa (R* the contact's effective radius),
α from e exactly (Antypov & Elliott, EPL 94 (2011) 50004):
:class:`perga.analytic.contact.HertzTsuji`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from perga.analytic.contact import End, HertzTsuji, effective_modulus, tsuji_alpha
from perga.contact.laws.base import ContactLaw
from perga.contact.laws.row import HERTZ


class Hertz(ContactLaw):
    """Hertz-Tsuji: damping α(e), stiffness from a duration or the materials' E and ν, a
    contact duration that shortens with speed (t_c ∝ v^{-1/5}) and size."""

    form = HERTZ
    stiffness_unit = "(4/3)E*, Pa"
    plan_unit = "Pa, (4/3)E*: k_n·√R* per contact"
    max_tangential_ratio = 2.0
    ratio_limit = "3(1 − ν)/(2 − ν) on the secant k_n√(R*δ), 1 to 2 for ν in (−1, 0.5]"
    from_materials = True
    mindlin = True
    peak_pressure = True

    def damping(self, e: float, end: End) -> float:
        """α = √5 ζ (``tsuji_alpha``)."""
        return tsuji_alpha(e, end)

    def kernel_damping(self, e: float, end: End) -> float:
        """D = α."""
        return self.damping(e, end)

    def stiffness_for_duration(
        self, t_c: float, e: float, m: float, r: float, v: float, end: End
    ) -> float:
        """(t_1/t_c)^{5/2}/√r, t_1 the duration at contact stiffness 1 (t_c ∝ (k_n√r)^{-2/5}
        at a given α; ``HertzTsuji.impact``)."""
        unit = HertzTsuji(1.0, self.damping(e, end), m, end).impact(v).duration
        return (unit / t_c) ** 2.5 / math.sqrt(r)

    def stiffness_from_materials(self, E: tuple[float, float], nu: tuple[float, float]) -> float:
        """(4/3)E* (``effective_modulus``; Johnson, Contact Mechanics (1985) §4.2)."""
        return 4.0 / 3.0 * effective_modulus(E, nu)

    def duration(
        self, k_n: float, e: float, m_eff: float, r_eff: float, v: float, end: End
    ) -> float:
        """At contact stiffness k_n√r_eff and speed v (``HertzTsuji.impact``)."""
        return (
            HertzTsuji(k_n * math.sqrt(r_eff), self.damping(e, end), m_eff, end).impact(v).duration
        )

    def normal_force(
        self, k_n: float, e: float, m_eff: float, r_eff: float, end: End
    ) -> Callable[[float, float], float]:
        """k δ^{3/2} + η δ^{1/4} δ̇, k = k_n√r_eff, η = α√(m_eff k) (``HertzTsuji``)."""
        law = HertzTsuji(k_n * math.sqrt(r_eff), self.damping(e, end), m_eff, end)
        k, eta = law.k_n, law.eta
        if end == "force":
            return lambda delta, rate: max(k * delta**1.5 + eta * delta**0.25 * rate, 0.0)
        return lambda delta, rate: k * delta**1.5 + eta * delta**0.25 * rate

    def sticking_stiffness(self, k_n: float, m_eff: float, r_eff: float, v: float) -> float:
        """The secant k_n√(R*δ_max) at the largest overlap of an elastic head-on impact at v,
        ½m_eff v² = (2/5)k_n√R* δ_max^{5/2}."""
        k = k_n * math.sqrt(r_eff)
        k *= (1.25 * m_eff * v * v / k) ** 0.2  # √δ_max
        return k
