"""The linear spring-dashpot law F = k_n δ + 2ζ√(k_n m_eff) δ̇ (Cundall & Strack 1979), k_n in
N/m, ζ from e in closed form (``end="overlap"``, Luding 2008 Granular Matter) or by root
(``end="force"``, Schwager & Pöschel 2007): :class:`perga.analytic.contact.LinearSpringDashpot`.
"""

from __future__ import annotations

from collections.abc import Callable

from perga.analytic.contact import End, LinearSpringDashpot
from perga.contact.laws.base import ContactLaw
from perga.contact.laws.row import LINEAR


class Linear(ContactLaw):
    """Linear spring-dashpot: damping ζ(e), a contact duration independent of speed and size."""

    form = LINEAR
    stiffness_unit = "N/m"
    plan_unit = "N/m"
    max_tangential_ratio = 4.0 / 3.0
    ratio_limit = "2(1 − ν)/(2 − ν) on tangent stiffnesses, 2/3 to 4/3 for ν in (−1, 0.5]"
    fixed_duration = True

    def damping(self, e: float, end: End) -> float:
        """ζ (:meth:`damping_ratio`)."""
        return self.damping_ratio(e, end)

    def kernel_damping(self, e: float, end: End) -> float:
        """D = 2ζ."""
        return 2.0 * self.damping_ratio(e, end)

    def stiffness_for_duration(
        self, t_c: float, e: float, m: float, r: float, v: float, end: End
    ) -> float:
        """k = m ω_n², ω_n = θ_end/(t_c√(1 − ζ²)) (``LinearSpringDashpot.from_duration``); r
        and v do not matter."""
        return LinearSpringDashpot.from_duration(t_c, e, m, end).k

    def duration(
        self, k_n: float, e: float, m_eff: float, r_eff: float, v: float, end: End
    ) -> float:
        """θ_end/ω_d (``LinearSpringDashpot.duration``), whatever r_eff and v."""
        return LinearSpringDashpot(k_n, self.damping_ratio(e, end), m_eff, end).duration

    def normal_force(
        self, k_n: float, e: float, m_eff: float, r_eff: float, end: End
    ) -> Callable[[float, float], float]:
        """k_n δ + c δ̇, c = 2ζ√(k_n m_eff) (``LinearSpringDashpot``), whatever r_eff."""
        law = LinearSpringDashpot(k_n, self.damping_ratio(e, end), m_eff, end)
        k, c = law.k, law.c
        if end == "force":
            return lambda delta, rate: max(k * delta + c * rate, 0.0)
        return lambda delta, rate: k * delta + c * rate

    def sticking_stiffness(self, k_n: float, m_eff: float, r_eff: float, v: float) -> float:
        """k_n itself."""
        return k_n
