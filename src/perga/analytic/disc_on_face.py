"""A disc that slips and rolls along a straight hammer face on a rotor at constant ω.

The face, the floor and the face's normal reaction are :class:`~perga.analytic.sliding.
BladeSlide`'s (rotating frame, x along the face, +y the direction of rotation, the granule's
centre on y = h, s = +1 on the leading face, −1 on the trailing one). The disc has radius a and
moment I = k m a² about its centre; Ω is its absolute angular velocity. The face touches it at
(0, −s a) from its centre, so the disc's material there moves along the face at the slip

    u = ẋ + s a (Ω − ω).

While it slips, face friction F = −f N sgn u (per unit mass) acts there:

    ẍ = ω²x + F_x + F,        Ω̇ = s F / (k a),

F_x the floor's friction on the centre (the floor acts on the centre only, as perga's floor
kick does). When u reaches 0 the disc rolls, (1 + k) ẍ = ω²x + F_x held by F = −k ẍ, while
k|ẍ| ≤ f N; beyond, it slips again. k → ∞ with u = ẋ is the sliding point of ``BladeSlide``
(``inertia_factor=None``); rolling from the start over no floor is its rolling disc.

Sources: rigid-body kinematics in a rotating frame (Goldstein, Classical Mechanics, ch. 4);
the slip-roll transition of a disc under Coulomb friction (Johnson, Contact Mechanics, 1985,
ch. 8).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from perga.analytic.sliding import BladeSlide

FloatArray = NDArray[np.float64]
DiscEvent = Literal["tip", "inner", "separated", "end"]
MAX_PHASES = 1000
"""Slip-roll phases before :meth:`DiscOnFace.integrate` gives up (a chattering transition)."""


@dataclass(frozen=True)
class DiscResult:
    """A disc's motion along the face until ``event``: t (s), x (m), v = ẋ (m/s) and its
    absolute spin Ω (rad/s) on the solver's grid, ``rolling`` (bool per point: the disc rolls
    there), the absolute speed of its centre at the end (m/s)."""

    t: FloatArray
    x: FloatArray
    v: FloatArray
    spin: FloatArray
    rolling: NDArray[np.bool_]
    event: DiscEvent
    absolute_exit_speed: float


@dataclass(frozen=True)
class DiscOnFace:
    """A disc of ``radius`` a (m) and inertia factor k = I/(m a²) (½ for a uniform disc) on
    the face of ``face`` (a sliding-point :class:`BladeSlide`: its ω, f, floor, side, offset
    h and ends)."""

    face: BladeSlide
    radius: float
    inertia_factor: float = 0.5

    def __post_init__(self) -> None:
        if self.face.inertia_factor is not None:
            raise ValueError("face must be a sliding-point BladeSlide (inertia_factor=None)")
        if not (self.radius > 0 and self.inertia_factor > 0):
            raise ValueError(
                f"radius and inertia_factor must be > 0 (got {self.radius}, {self.inertia_factor})"
            )

    @property
    def _side(self) -> int:
        return 1 if self.face.face == "leading" else -1

    def slip(self, v: float, spin: float) -> float:
        """u = ẋ + s a (Ω − ω), m/s."""
        return v + self._side * self.radius * (spin - self.face.omega)

    def _drive(self, x: float, v: float) -> float:
        """ω²x + F_x per unit mass, m/s²: what moves the centre along the face but friction."""
        return self.face.omega**2 * x + self.face.floor_force(x, v)[0]

    def rolling_acceleration(self, x: float, v: float) -> float:
        """ẍ of the rolling disc, m/s²."""
        return self._drive(x, v) / (1 + self.inertia_factor)

    def rolls(self, x: float, v: float) -> bool:
        """Whether friction can hold the disc rolling here: k|ẍ| ≤ f N."""
        normal = self.face.normal_per_mass(x, v)
        needed = self.inertia_factor * abs(self.rolling_acceleration(x, v))
        return normal >= 0 and needed <= self.face.face_friction * normal

    def _rhs(self, rolling: bool, sigma: float):
        k, a, s = self.inertia_factor, self.radius, self._side

        def rhs(_t: float, y: FloatArray) -> list[float]:
            x, v = y[0], y[1]
            if rolling:
                acc = self.rolling_acceleration(x, v)
                return [v, acc, -acc / (s * a)]
            force = -self.face.face_friction * max(self.face.normal_per_mass(x, v), 0.0) * sigma
            return [v, self._drive(x, v) + force, s * force / (k * a)]

        return rhs

    def integrate(
        self,
        x0: float,
        v0: float,
        spin0: float,
        t_end: float,
        rtol: float = 1e-10,
        atol: float = 1e-13,
    ) -> DiscResult:
        """Integrate with ``solve_ivp`` (DOP853), phase by phase (slipping each way, rolling),
        until the disc leaves the tip or the inner end, separates from the face (N < 0), or
        ``t_end`` (s)."""
        f = self.face
        if not f.inner <= x0 <= f.tip:
            raise ValueError(f"x0 must be on the face [{f.inner}, {f.tip}] m (got {x0})")
        ts, ys, modes = [np.array([0.0])], [np.array([[x0], [v0], [spin0]])], [np.array([False])]
        t, y = 0.0, np.array([x0, v0, spin0])
        for _ in range(MAX_PHASES):
            u = self.slip(y[1], y[2])
            still = abs(u) <= 1e-12 * max(1.0, abs(y[1]))
            rolling = still and self.rolls(y[0], y[1])
            # a disc at zero slip that cannot roll slips the way the drive pushes it
            sigma = math.copysign(1.0, self._drive(y[0], y[1]) if still else u)
            if len(ts) == 1:
                modes[0][0] = rolling
            if f.normal_per_mass(y[0], y[1]) < 0:
                return self._result(ts, ys, modes, "separated")
            event, t, y = self._phase(t, y, t_end, rolling, sigma, rtol, atol, ts, ys, modes)
            if event != "change":
                return self._result(ts, ys, modes, event)
        raise RuntimeError(f"more than {MAX_PHASES} slip-roll phases before t = {t} s")

    def _phase(self, t0, y0, t_end, rolling, sigma, rtol, atol, ts, ys, modes):
        f = self.face

        def tip(_t, y):
            return y[0] - f.tip

        def inner(_t, y):
            return y[0] - f.inner

        def separated(_t, y):
            return f.normal_per_mass(y[0], y[1])

        def change(_t, y):  # slipping: the slip reaches 0; rolling: friction reaches its cap
            if rolling:
                normal = f.normal_per_mass(y[0], y[1])
                return f.face_friction * normal - self.inertia_factor * abs(
                    self.rolling_acceleration(y[0], y[1])
                )
            return self.slip(y[1], y[2])

        events = (tip, inner, separated, change)
        for ev, direction in zip(events, (1, -1, -1, -1 if rolling else -sigma), strict=True):
            ev.terminal, ev.direction = True, direction
        sol = solve_ivp(self._rhs(rolling, sigma), (t0, t_end), y0, method="DOP853",
                        rtol=rtol, atol=atol, events=events)  # fmt: skip
        ts.append(sol.t[1:])
        ys.append(sol.y[:, 1:])
        modes.append(np.full(sol.t.size - 1, rolling))
        y = sol.y[:, -1].copy()
        for name, t_ev in zip(("tip", "inner", "separated", "change"), sol.t_events, strict=True):
            if t_ev.size:
                if name == "change" and not rolling:
                    # the slip is 0 here: set it exactly, so the next phase starts rolling
                    y[2] = f.omega - y[1] / (self._side * self.radius)
                return name, float(sol.t[-1]), y
        return "end", float(sol.t[-1]), y

    def _result(self, ts, ys, modes, event: DiscEvent) -> DiscResult:
        t = np.concatenate(ts)
        y = np.concatenate(ys, axis=1)
        w, h = self.face.omega, self.face.offset
        exit_speed = math.hypot(y[1, -1] - w * h, w * y[0, -1])
        return DiscResult(t, y[0], y[1], y[2], np.concatenate(modes), event, exit_speed)
