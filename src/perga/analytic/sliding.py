"""A granule sliding or rolling along a straight hammer face on a rotor at constant ω:
the physically consistent counterpart of the paper's eq. (1)-(8).

Rotating frame, origin on the rotor axis; x along the face (m), y across it, +y the direction of
rotation (ω > 0 counter-clockwise). The granule's centre moves on the line y = h (``offset``, m):
h = 0 is a face whose granule line passes through the axis. Per unit mass the forces are the
centrifugal ω²(x, h), the Coriolis 2ω(ẏ, −ẋ) = (0, −2ωẋ), the face's normal reaction and
Coulomb friction, and the floor's friction (horizontal rotor, floor normal force m g):

    y: s·N − 2ωẋ + ω²h + F_y = 0          s = +1 on the leading face (pushes the granule
    x: ẍ = ω²x + F_x − f·N·sgn(ẋ)            forward), s = −1 on the trailing face

so N = s(2ωẋ − ω²h − F_y) ≥ 0 while in contact. A co-rotating floor gives F = (−f_fl g sgn ẋ, 0)
and the motion is linear between sign changes of ẋ:

    ẍ + 2σsfωẋ − ω²x = −σ f_fl g + σ s f ω² h,   σ = sgn ẋ,

which for outward sliding on the leading face (σ = s = 1, h = 0) is the classical spreader-vane
equation ẍ + 2fωẋ − ω²x = −f_fl g, and for inward sliding on the trailing face is the paper's
eq. (8) ẍ + 2fωẋ − ω²x = +fg. A stationary floor resists the absolute velocity
(ẋ − ωh, ωx) and has no closed form. A disc rolling without slip (I = k m a²) obeys
(1 + k)ẍ = ω²x, held by face friction F = −k ẍ per unit mass while |F| ≤ f N.

Sources: the vane-spreader equations of Patterson & Reece (1962) and Hofstee (1992); rigid-body
kinematics in a rotating frame (Goldstein, Classical Mechanics, ch. 4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from perga.analytic.common import STANDARD_GRAVITY

FloatArray = NDArray[np.float64]
FloorMode = Literal["none", "corotating", "stationary"]
Face = Literal["leading", "trailing"]
SlideEvent = Literal["tip", "inner", "stuck", "separated", "end"]


@dataclass(frozen=True)
class LinearSlide:
    """x(t) = A e^{λ1 t} + B e^{λ2 t} + x_eq, the solution of ẍ + 2bẋ − q x = c, q > 0.

    Roots λ1,2 = −b ± √(b² + q) are real with opposite signs (s⁻¹); x_eq = −c/q (m).
    """

    b: float
    q: float
    c: float
    x0: float
    v0: float

    @property
    def roots(self) -> tuple[float, float]:
        """(λ1, λ2), s⁻¹."""
        root = math.sqrt(self.b**2 + self.q)
        return -self.b + root, -self.b - root

    @property
    def equilibrium(self) -> float:
        """x_eq = −c/q, m."""
        return -self.c / self.q

    @property
    def amplitudes(self) -> tuple[float, float]:
        """(A, B), m, from x(0) = x0, ẋ(0) = v0."""
        lam1, lam2 = self.roots
        d0 = self.x0 - self.equilibrium
        a = (self.v0 - lam2 * d0) / (lam1 - lam2)
        return a, d0 - a

    def displacement(self, t: ArrayLike) -> FloatArray:
        """x(t), m."""
        (lam1, lam2), (a, b) = self.roots, self.amplitudes
        t = np.asarray(t, dtype=float)
        return a * np.exp(lam1 * t) + b * np.exp(lam2 * t) + self.equilibrium

    def velocity(self, t: ArrayLike) -> FloatArray:
        """ẋ(t), m/s."""
        (lam1, lam2), (a, b) = self.roots, self.amplitudes
        t = np.asarray(t, dtype=float)
        return lam1 * a * np.exp(lam1 * t) + lam2 * b * np.exp(lam2 * t)

    def time_to_reach(self, x_target: float, t_max: float = 1e3) -> float:
        """First t > 0 with x(t) = x_target, s (root bracketed on a grid, then brentq to 1e-15).

        Returns ``math.inf`` if the target is not reached before ``t_max``.
        """
        lam1, _ = self.roots
        t_max = min(t_max, 700.0 / lam1)  # beyond, e^{λ1 t} overflows
        grid = np.concatenate(([0.0], np.geomspace(1e-12 * t_max, t_max, 4000)))
        gap = self.displacement(grid) - x_target
        crossing = np.nonzero(np.sign(gap[1:]) != np.sign(gap[:-1]))[0]
        if crossing.size == 0:
            return math.inf
        i = crossing[0]
        return brentq(
            lambda t: float(self.displacement(t)) - x_target,
            grid[i],
            grid[i + 1],
            xtol=1e-15,
            rtol=4 * np.finfo(float).eps,
        )


def frictionless_exit(omega: float, x0: float, v0: float, tip: float) -> tuple[float, float]:
    """Exit time (s) and relative exit speed (m/s) of a bead on a frictionless radial blade.

    x = x0 cosh ωt + (v0/ω) sinh ωt; the Jacobi integral ẋ² − ω²x² is constant, so
    ẋ_exit = √(v0² + ω²(tip² − x0²)); with y = e^{ωt_exit} the root of
    P y² − tip·y + Q = 0, P = (x0 + v0/ω)/2, Q = (x0 − v0/ω)/2. Requires 0 < x0 ≤ tip, v0 ≥ 0.
    """
    if not (omega > 0 and 0 < x0 <= tip and v0 >= 0):
        raise ValueError(
            f"need omega > 0, 0 < x0 <= tip and v0 >= 0 (got {omega}, {x0}, {tip}, {v0})"
        )
    p, q = (x0 + v0 / omega) / 2, (x0 - v0 / omega) / 2
    y = (tip + math.sqrt(tip**2 - 4 * p * q)) / (2 * p)
    return math.log(y) / omega, math.sqrt(v0**2 + omega**2 * (tip**2 - x0**2))


@dataclass(frozen=True)
class SlideResult:
    """A granule's motion along the face until an event.

    t (s), x (m), v = ẋ (m/s), normal = N/m (m/s²) on the solver's output grid; ``event`` is
    why it ended: ``tip`` (left the outer end), ``inner`` (reached the inner end), ``stuck``
    (static friction holds it for good), ``separated`` (N fell to 0: it flies off the face),
    ``end`` (t_end reached).
    """

    t: FloatArray
    x: FloatArray
    v: FloatArray
    normal: FloatArray
    event: SlideEvent
    absolute_exit_speed: float


@dataclass(frozen=True)
class BladeSlide:
    """A granule on a straight face of a rotor turning at constant ω (see the module docstring).

    omega (rad/s) > 0; face_friction f and floor_friction f_fl ≥ 0; floor: "none" (no floor
    contact: vertical-axis rotor without floor, or the frictionless limit), "corotating" or
    "stationary"; face: "leading" or "trailing"; offset h (m); gravity g (m/s²) presses on the
    floor; inertia_factor k = I/(m a²) for rolling without slip (½ disc, 2/5 sphere) or None
    for sliding (a point mass that does not turn relative to the face); inner, tip: the face's
    ends along x (m).
    """

    omega: float
    face_friction: float = 0.0
    floor_friction: float = 0.0
    floor: FloorMode = "none"
    face: Face = "leading"
    offset: float = 0.0
    gravity: float = STANDARD_GRAVITY
    inertia_factor: float | None = None
    inner: float = 0.0
    tip: float = math.inf

    def __post_init__(self) -> None:
        if not self.omega > 0:
            raise ValueError(f"omega must be > 0 rad/s (got {self.omega})")
        if self.face_friction < 0 or self.floor_friction < 0:
            raise ValueError(
                f"friction coefficients must be >= 0 (got face {self.face_friction}, "
                f"floor {self.floor_friction})"
            )
        if self.floor not in ("none", "corotating", "stationary"):
            raise ValueError(f"floor must be none, corotating or stationary (got {self.floor!r})")
        if self.face not in ("leading", "trailing"):
            raise ValueError(f"face must be leading or trailing (got {self.face!r})")
        if self.inertia_factor is not None and (self.inertia_factor <= 0 or self.floor != "none"):
            raise ValueError(
                "rolling needs inertia_factor > 0 and floor='none' "
                f"(got {self.inertia_factor}, {self.floor!r})"
            )
        if not self.inner < self.tip:
            raise ValueError(f"inner must be < tip (got {self.inner}, {self.tip})")

    @property
    def _side(self) -> int:
        return 1 if self.face == "leading" else -1

    def floor_force(self, x: float, v: float) -> tuple[float, float]:
        """Floor friction per unit mass in the rotating basis, m/s²."""
        if self.floor == "none" or self.floor_friction == 0:
            return 0.0, 0.0
        cap = self.floor_friction * self.gravity
        if self.floor == "corotating":
            return -cap * float(np.sign(v)), 0.0
        ux, uy = v - self.omega * self.offset, self.omega * x
        speed = math.hypot(ux, uy)
        return (0.0, 0.0) if speed == 0 else (-cap * ux / speed, -cap * uy / speed)

    def normal_per_mass(self, x: float, v: float) -> float:
        """N/m, m/s²: the face reaction needed to keep the granule on the face."""
        _, fy = self.floor_force(x, v)
        w = self.omega
        return self._side * (2 * w * v - w**2 * self.offset - fy)

    def acceleration(self, x: float, v: float) -> float:
        """ẍ, m/s², while the granule slides (v ≠ 0) or rolls along the face."""
        w = self.omega
        if self.inertia_factor is not None:
            return w**2 * x / (1 + self.inertia_factor)
        fx, _ = self.floor_force(x, v)
        friction = self.face_friction * max(self.normal_per_mass(x, v), 0.0) * float(np.sign(v))
        return w**2 * x + fx - friction

    def rolling_friction_ratio(self, x: float, v: float) -> float:
        """|F|/N for the rolling disc (m/s² over m/s²); rolling holds while this is ≤ f."""
        if self.inertia_factor is None:
            raise ValueError("rolling_friction_ratio needs inertia_factor (a rolling granule)")
        needed = self.inertia_factor * abs(self.acceleration(x, v))
        normal = self.normal_per_mass(x, v)
        return math.inf if normal <= 0 else needed / normal

    def closed_form(self, x0: float, v0: float) -> LinearSlide:
        """The exact solution while ẋ keeps the sign of v0 (≠ 0) and N ≥ 0.

        Available for floor "none" and "corotating" (a stationary floor has no closed form).
        """
        if self.floor == "stationary":
            raise ValueError("a stationary floor has no closed form: use integrate()")
        w = self.omega
        if self.inertia_factor is not None:
            return LinearSlide(0.0, w**2 / (1 + self.inertia_factor), 0.0, x0, v0)
        if v0 == 0:
            raise ValueError("closed_form needs v0 != 0 (the sign of ẋ selects the branch)")
        sigma, s, f = float(np.sign(v0)), self._side, self.face_friction
        floor_f = self.floor_friction if self.floor == "corotating" else 0.0
        c = -sigma * floor_f * self.gravity + sigma * s * f * w**2 * self.offset
        return LinearSlide(sigma * s * f * w, w**2, c, x0, v0)

    def _drive(self, x: float) -> float:
        """Force per unit mass along the face on a granule at rest there, less static friction."""
        fx, _ = self.floor_force(x, 0.0)
        return self.omega**2 * x + fx

    def _static_hold(self, x: float) -> bool:
        """Does static friction hold a granule at rest at x? (the same f static and kinetic)."""
        capacity = self.face_friction * max(self.normal_per_mass(x, 0.0), 0.0)
        if self.floor == "corotating":
            capacity += self.floor_friction * self.gravity
        return abs(self._drive(x)) <= capacity

    def integrate(
        self, x0: float, v0: float, t_end: float, rtol: float = 1e-10, atol: float = 1e-13
    ) -> SlideResult:
        """Integrate with ``solve_ivp`` (DOP853) and events until the granule leaves the tip or
        the inner end, separates from the face, sticks, or t_end (s) is reached.

        A granule that stops (ẋ = 0) either sticks (static friction suffices) or restarts in the
        direction of the net force; a restart that would need N < 0 is a separation.
        """
        if not self.inner <= x0 <= self.tip:
            raise ValueError(f"x0 must be on the face [{self.inner}, {self.tip}] m (got {x0})")
        ts, xs, vs = [np.array([0.0])], [np.array([x0])], [np.array([v0])]
        t, x, v = 0.0, x0, v0
        while True:
            if v == 0:
                if self._static_hold(x):
                    return self._result(ts, xs, vs, "stuck")
                # restart: an infinitesimal velocity along the net drive selects the branch
                v = math.copysign(1e-300, self._drive(x))
            if self.inertia_factor is None and self.normal_per_mass(x, v) < 0:
                return self._result(ts, xs, vs, "separated")
            event, t, x, v = self._integrate_phase(t, x, v, t_end, rtol, atol, ts, xs, vs)
            if event != "stopped":
                return self._result(ts, xs, vs, event)
            v = 0.0

    def _integrate_phase(self, t0, x0, v0, t_end, rtol, atol, ts, xs, vs):
        sign = float(np.sign(v0))

        def rhs(_t: float, y: NDArray[np.float64]) -> list[float]:
            # the branch (sign of ẋ) is frozen during a phase; the stop event ends it
            return [y[1], self.acceleration(y[0], sign * max(sign * y[1], 1e-300))]

        def hit_tip(_t, y):
            return y[0] - self.tip

        def hit_inner(_t, y):
            return y[0] - self.inner

        def stopped(_t, y):
            return y[1]

        def separated(_t, y):
            return self.normal_per_mass(y[0], y[1]) if self.inertia_factor is None else 1.0

        events = [hit_tip, hit_inner, stopped, separated]
        for ev, direction in zip(events, (1, -1, -sign, -1), strict=True):
            ev.terminal, ev.direction = True, direction
        sol = solve_ivp(
            rhs,
            (t0, t_end),
            [x0, v0],
            method="DOP853",
            rtol=rtol,
            atol=atol,
            events=events,
            dense_output=False,
        )
        ts.append(sol.t[1:])
        xs.append(sol.y[0, 1:])
        vs.append(sol.y[1, 1:])
        t, x, v = float(sol.t[-1]), float(sol.y[0, -1]), float(sol.y[1, -1])
        for name, t_ev in zip(("tip", "inner", "stopped", "separated"), sol.t_events, strict=True):
            if t_ev.size:
                # with h = 0 on the trailing face N = −2ωẋ: N and ẋ vanish together, a stop
                if name == "separated" and abs(v) <= 1e-9 * abs(v0):
                    name = "stopped"
                return name, t, x, v
        return "end", t, x, v

    def _result(self, ts, xs, vs, event: SlideEvent) -> SlideResult:
        t, x, v = (np.concatenate(a) for a in (ts, xs, vs))
        normal = np.array([self.normal_per_mass(xi, vi) for xi, vi in zip(x, v, strict=True)])
        w = self.omega
        exit_speed = math.hypot(v[-1] - w * self.offset, w * x[-1])
        return SlideResult(t, x, v, normal, event, exit_speed)
