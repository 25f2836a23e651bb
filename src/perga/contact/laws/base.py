"""What every normal contact law offers (:class:`ContactLaw`), SI units.

A law is tuned to a pair's restitution e under a contact-end criterion ``end`` ("force": the
force is clamped at zero and the contact ends when it returns to zero; "overlap": it ends when
the overlap does; :mod:`perga.analytic.contact`). Its normal stiffness k_n comes from a contact
duration, is given, or (some laws) comes from the materials' E and ν; the kernel integrates it
as one of its normal-force forms (:mod:`perga.contact.laws.row`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import ClassVar

import numpy as np

from perga.analytic.contact import FORCE_END_MIN_RESTITUTION, End, damping_ratio
from perga.contact.laws.row import (
    N_PARAMS,
    P_CLAMP,
    P_DAMP,
    P_DAMPT,
    P_HERTZ,
    P_KN,
    P_KT,
    P_MU,
    P_MUR,
)


class ContactLaw(ABC):
    """One normal contact law: its damping from e, stiffness, duration, k_t/k_n limits and
    kernel row. Arguments: e, restitution; end, the contact-end criterion; m, m_eff, kg (a
    granule's mass, a contact's reduced mass); r, r_eff, m (a granule's radius, a contact's
    effective radius R*); v, the fastest relative normal speed, m/s (> 0); k_n, the normal
    stiffness in :attr:`stiffness_unit`. Methods taking e raise ValueError where the law cannot
    reach it (:meth:`reachable`)."""

    form: ClassVar[int]
    """The kernel's normal-force form (:data:`~perga.contact.laws.row.LINEAR`, ``HERTZ``)."""
    stiffness_unit: ClassVar[str]
    """What k_n is: its unit (and quantity), as the case file's messages name it."""
    plan_unit: ClassVar[str]
    """The same as the step plan states it (summary.json's contacts)."""
    max_tangential_ratio: ClassVar[float]
    """Largest k_t/k_n: an elastic solid's on this law's stiffness, as ν → −1."""
    ratio_limit: ClassVar[str]
    """That k_t/k_n's formula and range in words (Mindlin 1949)."""
    default_tangential_ratio: ClassVar[float] = 2.0 / 7.0
    """k_t/k_n where nothing gives one: LAMMPS ``pair_style gran/hooke/history``'s k_t for
    k_t = NULL. For spheres it equals the tangential and normal contact periods (tangential
    effective mass m/(1 + m r²/I) = 2m/7); for discs (I = m r²/2) the period-matching ratio
    would be 1/3; 2/7 is kept so that perga's runs are comparable with LAMMPS at the same
    inputs."""
    fixed_duration: ClassVar[bool] = False
    """Whether a contact's duration depends on k_n, e and m_eff alone, not on its radius or
    speed: a duration and a mass then give k_n (:meth:`stiffness_for_duration`'s r and v
    unused)."""
    from_materials: ClassVar[bool] = False
    """Whether k_n may come from the materials' E and ν (:meth:`stiffness_from_materials`)."""
    mindlin: ClassVar[bool] = False
    """Whether Mindlin's k_t/k_n (:func:`perga.analytic.contact.mindlin_ratio`) applies."""
    peak_pressure: ClassVar[bool] = False
    """Whether its impacts report the peak contact pressure of the peak force (Hertz's)."""

    def damping_ratio(self, e: float, end: End) -> float:
        """ζ giving restitution e: of the law's linear oscillator (Hertz-Tsuji: α/√5, Antypov &
        Elliott 2011), dimensionless; ``perga.analytic.contact.damping_ratio``. The step plan
        scales its steps per contact with it."""
        return damping_ratio(e, end)

    @abstractmethod
    def damping(self, e: float, end: End) -> float:
        """The law's own damping coefficient giving e (linear ζ, Hertz-Tsuji α), dimensionless:
        the step plan's and the granule-polygon table's."""

    @abstractmethod
    def kernel_damping(self, e: float, end: End) -> float:
        """The pair table's dimensionless damping D giving e (:data:`~.row.P_DAMP`)."""

    def reachable(self, end: End) -> tuple[float, float]:
        """(low, high): the restitutions e in (low, high] the law reaches under ``end``:
        (e⁻², 1] for "force" (ζ < 1, Schwager & Pöschel 2007), (0, 1] for "overlap"."""
        return (FORCE_END_MIN_RESTITUTION if end == "force" else 0.0, 1.0)

    @abstractmethod
    def stiffness_for_duration(
        self, t_c: float, e: float, m: float, r: float, v: float, end: End
    ) -> float:
        """The k_n with which a granule of mass m and radius r striking a rigid wall head-on
        at speed v (up to v: a speed-dependent contact is shortest at v) with restitution e
        stays t_c (s) in contact."""

    def stiffness_from_materials(self, E: tuple[float, float], nu: tuple[float, float]) -> float:
        """k_n of two materials of Young's moduli E (Pa) and Poisson's ratios ν, for a law that
        takes it from them (:attr:`from_materials`); ValueError for the others."""
        raise ValueError(f"{type(self).__name__} takes no stiffness from the materials")

    @abstractmethod
    def duration(
        self, k_n: float, e: float, m_eff: float, r_eff: float, v: float, end: End
    ) -> float:
        """Duration of a head-on contact of stiffness k_n and restitution e at speed v, s."""

    @abstractmethod
    def normal_force(
        self, k_n: float, e: float, m_eff: float, r_eff: float, end: End
    ) -> Callable[[float, float], float]:
        """F(δ, δ̇): the normal force of a contact of stiffness k_n, restitution e, reduced mass
        m_eff and effective radius r_eff at overlap δ (m) and approach rate δ̇ (m/s), N,
        clamped at 0 when the contact ends at zero force: the law in closed form, apart from
        the kernel's discretisation of it (an independent reference)."""

    @abstractmethod
    def sticking_stiffness(self, k_n: float, m_eff: float, r_eff: float, v: float) -> float:
        """The normal stiffness a sticking contact's tangential spring is k_t/k_n of, at its
        stiffest in a head-on impact at speed v, N/m."""

    def row(
        self,
        e: float,
        k_n: float,
        *,
        friction: float,
        rolling: float,
        kt_ratio: float,
        zeta_t: float,
        end: End,
    ) -> np.ndarray:
        """The kernel's pair-table row (:mod:`~perga.contact.laws.row`) of a pair of
        restitution e, stiffness k_n, friction f, rolling μ_r, k_t = kt_ratio·k_n and
        tangential damping ratio ζ_t, for ``end`` (the force clamped at zero for "force")."""
        row = np.zeros(N_PARAMS)
        row[P_KN] = k_n
        row[P_DAMP] = self.kernel_damping(e, end)
        row[P_KT] = kt_ratio * k_n
        row[P_DAMPT] = zeta_t
        row[P_MU] = friction
        row[P_MUR] = rolling
        row[P_HERTZ] = self.form
        row[P_CLAMP] = 1.0 if end == "force" else 0.0
        return row
