"""The paper's model exactly as published (Syromiatnykov, Bielykh & Kharchenko 2026).

Source: "Development of an analytical model for predicting the trajectory and energy
dissipation of bee bread granules in a rotary impact separator", Technology Audit and
Production Reserves 1(1(87)) 23-31, doi:10.15587/2706-5448.2026.353169. Equation numbers
below are the paper's.

Everything here reproduces the printed equations, including their errors, so that the
paper's claims can be evaluated as the authors computed them. Where an equation is wrong the
docstring says so; the physically consistent models are in :mod:`perga.analytic.sliding`,
:mod:`perga.analytic.impact` and :mod:`perga.analytic.hammer`.
``docs/explanation/paper-notes.md`` lists every error with numbers.

Symbols: x relative radial displacement in the rotating frame (m), ω rotor angular velocity
(rad/s), f friction coefficient (-), g gravitational acceleration (m/s²), R hinge radius (m),
φ0 rotor phase at the impact (rad).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perga.analytic.common import STANDARD_GRAVITY

FloatArray = NDArray[np.float64]


def _check_rate_inputs(omega: float, f: float) -> None:
    if not omega > 0:
        raise ValueError(f"omega must be > 0 rad/s (got {omega})")
    if not f >= 0:
        raise ValueError(f"f must be >= 0 (got {f})")


def paper_discriminant(omega: float, f: float) -> float:
    """Eq. (10): D = (2fω)² + 4ω² = 4ω²(f² + 1), s⁻².

    D > 0 for every real ω ≠ 0 and f: the roots (11) are always real, so the radial motion
    of eq. (8) never oscillates (the paper's "damped oscillation" is impossible).
    """
    _check_rate_inputs(omega, f)
    return 4.0 * omega**2 * (f**2 + 1.0)


def paper_roots(omega: float, f: float) -> tuple[float, float]:
    """Eq. (11): λ1,2 = −fω ± ω√(f² + 1), s⁻¹ (λ1 > 0 > λ2: a saddle, not a decay).

    λ1 = ω(√(1+f²) − f) is the growth rate and |λ2| = ω(f + √(1+f²)) the decay rate.
    """
    _check_rate_inputs(omega, f)
    root = omega * math.sqrt(f * f + 1.0)
    return -f * omega + root, -f * omega - root


def paper_wronskian(omega: float, f: float, t: ArrayLike, printed: bool = False) -> FloatArray:
    """Wronskian of {e^{λ1 t}, e^{λ2 t}}, s⁻¹.

    Eq. (15) (correct): W = (λ2 − λ1)·e^{(λ1+λ2)t} = −2ω√(f²+1)·e^{−2fωt}.
    Eq. (16) as printed (``printed=True``): W = +2ω√(f²+1)·e^{−2fωt}, the wrong sign; the
    paper's eq. (17)-(18) drop a compensating minus sign, so (19)-(22) come out right.
    """
    lam1, lam2 = paper_roots(omega, f)
    t = np.asarray(t, dtype=float)
    w = (lam2 - lam1) * np.exp((lam1 + lam2) * t)
    return -w if printed else w


def paper_particular_solution(omega: float, f: float, g: float = STANDARD_GRAVITY) -> float:
    """Eq. (21)-(23) evaluated: x_p = u1·e^{λ1 t} + u2·e^{λ2 t} = −fg/ω², m (time independent).

    Computed from the paper's own u1, u2 (eq. 21, 22) rather than asserted, so that a test can
    check it equals the constant in eq. (24) and solves eq. (8).
    """
    lam1, lam2 = paper_roots(omega, f)
    scale = f * g / (2.0 * omega * math.sqrt(f * f + 1.0))
    # u1·e^{λ1 t} and u2·e^{λ2 t} carry e^{(λ1+λ2+2fω)t} = e^0 = 1.
    return scale / (lam2 + 2.0 * f * omega) - scale / (lam1 + 2.0 * f * omega)


@dataclass(frozen=True)
class PaperRadialMotion:
    """Eq. (24)-(27) and (36): x(t) = C1·e^{λ1 t} + (x0 + fg/ω² − C1)·e^{λ2 t} − fg/ω².

    The general solution of eq. (8), ẍ + 2fωẋ − ω²x = fg, with x(0) = x0 (m) and the free
    constant C1 (m) that the paper never fixes. Build it from a launch velocity with
    :meth:`from_launch_velocity` or take the paper's decaying branch (C1 = 0) with
    :meth:`decaying_branch`; the latter needs the exact launch velocity ẋ(0) = λ2(x0 + fg/ω²).
    Any other start grows like e^{λ1 t}.

    Physically, eq. (8) holds only for a granule sliding inward (ẋ < 0) on the trailing face of
    a radial hammer with a co-rotating floor and one friction coefficient for face and floor.
    """

    omega: float
    f: float
    x0: float
    c1: float
    g: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        _check_rate_inputs(self.omega, self.f)

    @classmethod
    def from_launch_velocity(
        cls, omega: float, f: float, x0: float, v0: float, g: float = STANDARD_GRAVITY
    ) -> PaperRadialMotion:
        """The solution with x(0) = x0 (m) and ẋ(0) = v0 (m/s)."""
        lam1, lam2 = paper_roots(omega, f)
        c1 = (v0 - lam2 * (x0 + f * g / omega**2)) / (lam1 - lam2)
        return cls(omega, f, x0, c1, g)

    @classmethod
    def decaying_branch(
        cls, omega: float, f: float, x0: float, g: float = STANDARD_GRAVITY
    ) -> PaperRadialMotion:
        """The C1 = 0 branch the paper's figures show (eq. 27 with C1 = 0)."""
        return cls(omega, f, x0, 0.0, g)

    @property
    def roots(self) -> tuple[float, float]:
        """(λ1, λ2), s⁻¹, eq. (11)."""
        return paper_roots(self.omega, self.f)

    @property
    def offset(self) -> float:
        """fg/ω², m: eq. (24)'s constant, the rest point is x = −fg/ω²."""
        return self.f * self.g / self.omega**2

    @property
    def c2(self) -> float:
        """C2 = x0 + fg/ω² − C1, m, eq. (26)."""
        return self.x0 + self.offset - self.c1

    @property
    def launch_velocity(self) -> float:
        """ẋ(0) = λ1 C1 + λ2 C2, m/s."""
        lam1, lam2 = self.roots
        return lam1 * self.c1 + lam2 * self.c2

    def displacement(self, t: ArrayLike) -> FloatArray:
        """x(t), m, eq. (27)."""
        lam1, lam2 = self.roots
        t = np.asarray(t, dtype=float)
        return self.c1 * np.exp(lam1 * t) + self.c2 * np.exp(lam2 * t) - self.offset

    def velocity(self, t: ArrayLike) -> FloatArray:
        """ẋ(t), m/s, eq. (36)."""
        lam1, lam2 = self.roots
        t = np.asarray(t, dtype=float)
        return lam1 * self.c1 * np.exp(lam1 * t) + lam2 * self.c2 * np.exp(lam2 * t)

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """ẍ(t), m/s²."""
        lam1, lam2 = self.roots
        t = np.asarray(t, dtype=float)
        return lam1**2 * self.c1 * np.exp(lam1 * t) + lam2**2 * self.c2 * np.exp(lam2 * t)

    def residual(self, t: ArrayLike) -> FloatArray:
        """ẍ + 2fωẋ − ω²x − fg, m/s²: zero where x(t) solves eq. (8)."""
        w, f = self.omega, self.f
        return (
            self.acceleration(t)
            + 2 * f * w * self.velocity(t)
            - w**2 * self.displacement(t)
            - f * self.g
        )


def paper_rotor_angle(omega: float, t: ArrayLike, phi0: float = 0.0) -> FloatArray:
    """Eq. (28): φ(t) = φ0 + ωt, rad."""
    return phi0 + omega * np.asarray(t, dtype=float)


def paper_trajectory(
    motion: PaperRadialMotion, t: ArrayLike, hinge_radius: float, phi0: float = 0.0
) -> tuple[FloatArray, FloatArray]:
    """Eq. (30)-(32): X = (R + x)cos φ, Y = (R + x)sin φ in the fixed frame, m.

    Note eq. (29) r = R + x is inconsistent with eq. (8), whose centrifugal term ω²x measures x
    from the rotation axis: the two agree only for R = 0.
    """
    r = hinge_radius + motion.displacement(t)
    phi = paper_rotor_angle(motion.omega, t, phi0)
    return r * np.cos(phi), r * np.sin(phi)


def paper_velocity_components(
    motion: PaperRadialMotion, t: ArrayLike, hinge_radius: float, phi0: float = 0.0
) -> tuple[FloatArray, FloatArray]:
    """Eq. (35): Ẋ = ẋ cos φ − ω(R+x) sin φ, Ẏ = ẋ sin φ + ω(R+x) cos φ, m/s."""
    x, xd = motion.displacement(t), motion.velocity(t)
    phi = paper_rotor_angle(motion.omega, t, phi0)
    r = hinge_radius + x
    w = motion.omega
    return xd * np.cos(phi) - w * r * np.sin(phi), xd * np.sin(phi) + w * r * np.cos(phi)


def paper_speed(
    motion: PaperRadialMotion, t: ArrayLike, hinge_radius: float, printed: bool = False
) -> FloatArray:
    """Eq. (40): V = √(ẋ² + ω²(R + x)²), m/s.

    ``printed=True`` reproduces the expansion (38) as printed, which writes ωx where eq. (35)
    has ω(R + x), i.e. V = √(ẋ² + ω²x²): it drops R.
    """
    x, xd = motion.displacement(t), motion.velocity(t)
    r = x if printed else hinge_radius + x
    return np.sqrt(xd**2 + (motion.omega * r) ** 2)


def paper_impulse_law(
    m: float, v0n: float, v0t: float, e: float, f: float
) -> tuple[float, float, float, float]:
    """Eq. (56)-(59) as printed: v1n = −e·v0n, J_n = −m(1+e)v0n, J_t = −f|J_n| sgn(v0t).

    Returns (v1n, v1t, J_n, J_t) in m/s and N·s. The law is that of a fixed, infinitely heavy
    wall (the hammer mass appears nowhere), and J_t has no sticking cap: for |v0t| below
    f(1+e)|v0n| it reverses the tangential velocity, which Coulomb friction cannot do. The
    physically consistent laws are in :mod:`perga.analytic.impact`.
    """
    jn = -m * (1.0 + e) * v0n
    jt = -f * abs(jn) * math.copysign(1.0, v0t) if v0t != 0 else 0.0
    return -e * v0n, v0t + jt / m, jn, jt


ResetRule = Literal["continuous", "scaled"]


@dataclass(frozen=True)
class PaperSuccessiveImpacts:
    """Eq. (61)-(65): four (or n) successive impacts, each restarting an exponential decay.

    Segment i (t ≥ t_i): x_i(t) = x0_i·e^{−β(t − t_i)} (61), φ_i(t) = ω(t − t_i) + φ0_i (62),
    X_i, Y_i = (R + x_i)(cos φ_i, sin φ_i) (63)-(64), v_i = √(ẋ_i² + ω²(R + x_i)²) (65).

    The paper does not say how x0_{i+1} follows from segment i; the rule is explicit here:
    ``"continuous"`` takes x0_{i+1} = x_i(t_{i+1}); ``"scaled"`` takes x0_{i+1} = κ·x_i(t_{i+1}).
    φ0_{i+1} = φ_i(t_{i+1}) (the rotor keeps turning). β (s⁻¹) is a free parameter: the paper
    never relates it to the roots (11).
    """

    beta: float
    omega: float
    hinge_radius: float
    x01: float
    impact_times: tuple[float, ...]
    reset: ResetRule = "continuous"
    kappa: float = 1.0
    phi01: float = 0.0

    def __post_init__(self) -> None:
        times = self.impact_times
        if len(times) < 1 or any(b <= a for a, b in pairwise(times)):
            raise ValueError(f"impact_times must be increasing (got {times})")
        if self.reset not in ("continuous", "scaled"):
            raise ValueError(f"reset must be 'continuous' or 'scaled' (got {self.reset!r})")

    @property
    def initial_offsets(self) -> FloatArray:
        """x0_i for every impact i, m."""
        x0 = [self.x01]
        for a, b in pairwise(self.impact_times):
            carried = x0[-1] * math.exp(-self.beta * (b - a))
            x0.append(carried * (self.kappa if self.reset == "scaled" else 1.0))
        return np.array(x0)

    def segment(self, i: int, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """(x_i, ẋ_i, φ_i) of segment i (0-based) at times t ≥ t_i: m, m/s, rad."""
        t = np.asarray(t, dtype=float) - self.impact_times[i]
        x = self.initial_offsets[i] * np.exp(-self.beta * t)
        phi0 = self.phi01 + self.omega * (self.impact_times[i] - self.impact_times[0])
        return x, -self.beta * x, phi0 + self.omega * t

    def speed_after_impact(self) -> FloatArray:
        """v_i(t_i) from eq. (65) for every impact, m/s."""
        x0 = self.initial_offsets
        return np.sqrt((self.beta * x0) ** 2 + (self.omega * (self.hinge_radius + x0)) ** 2)

    def energy_after_impact(self, m: float) -> FloatArray:
        """½·m·v_i(t_i)², J: the mechanical energy after each impact (Fig. 5b)."""
        return 0.5 * m * self.speed_after_impact() ** 2


def paper_cumulative_loss(e: float, n_impacts: int) -> FloatArray:
    """Energy left after each of n impacts when each keeps a fraction e² (the paper's recursion
    "assuming constant restitution e"), as a fraction of the energy before the first: e^{2i}."""
    if not 0 <= e <= 1:
        raise ValueError(f"e must be in [0, 1] (got {e})")
    return np.array([e ** (2 * i) for i in range(1, n_impacts + 1)])


def fit_successive_decay(radii: Sequence[float], interval: float) -> tuple[float, float]:
    """(x01 in m, β in s⁻¹) that best fit observed post-impact offsets, ``continuous`` reset rule.

    With equal intervals Δt the offsets form a geometric sequence x0_i = x01·e^{−β(i−1)Δt}; the
    fit is least squares on ln x0_i (relative errors weigh equally).
    """
    if interval <= 0:
        raise ValueError(f"interval must be > 0 s (got {interval})")
    logs = np.log(np.asarray(radii, dtype=float))
    slope, intercept = np.polyfit(np.arange(len(logs)), logs, 1)
    return math.exp(intercept), -slope / interval
