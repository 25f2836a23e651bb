"""A granule's free flight over the floor of a horizontal rotor: Coulomb friction against its
velocity relative to the floor and quadratic air drag, in the fixed frame.

    ṙ = v,    v̇ = −f g u/|u| − k |v| v,    u = v − w,

w the floor's velocity under the granule: ω ẑ × r for a floor turning with the rotor at ω,
0 for a stationary one (no floor: f = 0). k = ½ ρ C_d A / m (1/m) for drag on the granule's
cross-section A. A stationary floor without drag gives a straight line slowed at f g
(:func:`perga.stats.trajectory.free_flight`); drag alone |v| = v0/(1 + k v0 t); a turning floor
has no closed form. The flight ends when u reaches 0 (the floor then carries the granule:
``caught``).

Sources: Coulomb sliding friction (Johnson, Contact Mechanics, 1985, ch. 7); quadratic drag
(Batchelor, An Introduction to Fluid Dynamics, 1967, §5.11).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from perga.analytic.common import STANDARD_GRAVITY

FloatArray = NDArray[np.float64]
FlightEvent = Literal["end", "caught"]


@dataclass(frozen=True)
class FlightResult:
    """A flight until ``event``: t (s), r (n, 2; m) and v (n, 2; m/s) on the solver's grid."""

    t: FloatArray
    r: FloatArray
    v: FloatArray
    event: FlightEvent


@dataclass(frozen=True)
class FloorFlight:
    """Flight over a floor turning at ``omega`` (rad/s; 0: a stationary floor) with friction
    coefficient ``friction`` f (0: no floor), gravity ``gravity`` g (m/s²) pressing on it, and
    drag coefficient ``drag`` k = ½ ρ C_d A / m (1/m, 0: no drag)."""

    omega: float = 0.0
    friction: float = 0.0
    gravity: float = STANDARD_GRAVITY
    drag: float = 0.0

    def __post_init__(self) -> None:
        if self.friction < 0 or self.drag < 0 or self.gravity < 0:
            raise ValueError(
                f"friction, drag and gravity must be >= 0 (got {self.friction}, {self.drag}, "
                f"{self.gravity})"
            )

    def relative(self, r: FloatArray, v: FloatArray) -> FloatArray:
        """u = v − ω ẑ × r, m/s."""
        return v - self.omega * np.array([-r[1], r[0]])

    def _rhs(self, _t: float, y: FloatArray) -> FloatArray:
        r, v = y[:2], y[2:]
        u = self.relative(r, v)
        speed = math.hypot(u[0], u[1])
        a = -self.friction * self.gravity * u / speed if speed > 0 else np.zeros(2)
        a = a - self.drag * math.hypot(v[0], v[1]) * v
        return np.concatenate((v, a))

    def integrate(
        self,
        r0: tuple[float, float],
        v0: tuple[float, float],
        t_end: float,
        rtol: float = 1e-10,
        atol: float = 1e-13,
    ) -> FlightResult:
        """Integrate with ``solve_ivp`` (DOP853) from r0 (m), v0 (m/s) for ``t_end`` (s), or
        until the floor catches the granule (|u| falls to 1e-9 of its start: friction would
        then hold it or restart it, which this flight does not follow)."""
        y0 = np.array([*r0, *v0], dtype=float)
        u0 = float(np.hypot(*self.relative(y0[:2], y0[2:])))

        def caught(_t: float, y: FloatArray) -> float:
            return float(np.hypot(*self.relative(y[:2], y[2:]))) - 1e-9 * u0

        caught.terminal, caught.direction = True, -1  # type: ignore[attr-defined]
        events = [caught] if self.friction > 0 and u0 > 0 else None
        sol = solve_ivp(self._rhs, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=atol,
                        events=events)  # fmt: skip
        event: FlightEvent = "caught" if events and sol.t_events[0].size else "end"
        return FlightResult(sol.t, sol.y[:2].T, sol.y[2:].T, event)
