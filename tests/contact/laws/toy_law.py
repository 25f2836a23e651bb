"""A contact law for the tests only, kept out of the package: a linear spring-dashpot damped
as if every contact ended at zero overlap, ζ = −ln e/√(π² + ln² e) (Luding 2008 Granular
Matter), whatever ``end``. With the force clamped at zero (``end = "force"``) it rebounds
harder than e: restitution(ζ, "force") (Schwager & Pöschel 2007), e.g. 0.5503 for e = 0.5;
it reaches any e in (0, 1] under either end. Registered by one line of the registry
(tests/contact/laws/test_new_law.py), it is what adding a law takes: this module."""

from perga.analytic.contact import End, damping_ratio
from perga.contact.laws.linear import Linear


class OverlapDamped(Linear):
    """Linear spring-dashpot with the zero-overlap ζ(e) under either end."""

    def damping_ratio(self, e: float, end: End) -> float:
        """ζ of a contact that ends at zero overlap, whatever ``end``."""
        return damping_ratio(e, "overlap")

    def reachable(self, end: End) -> tuple[float, float]:
        """Any e in (0, 1]: ζ < 1 for every e > 0."""
        return (0.0, 1.0)

    def stiffness_for_duration(
        self, t_c: float, e: float, m: float, r: float, v: float, end: End
    ) -> float:
        """The k that makes :meth:`duration` t_c: a linear contact's duration goes as 1/√k."""
        return (self.duration(1.0, e, m, r, v, end) / t_c) ** 2
