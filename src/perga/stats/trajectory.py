"""Trajectory statistics: radial coordinate, blade frame, amplitude left, fitted rates, and the
free flight of a granule over a stationary Coulomb floor (SI units)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import curve_fit

FloatArray = NDArray[np.float64]


def radial(x: ArrayLike, y: ArrayLike) -> FloatArray:
    """Distance from the rotor axis r = √(x² + y²), m."""
    return np.hypot(np.asarray(x, dtype=float), np.asarray(y, dtype=float))


def blade_frame(
    x: ArrayLike, y: ArrayLike, vx: ArrayLike, vy: ArrayLike, theta: ArrayLike, omega: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Coordinates in a frame turning with a radial blade at angle θ(t) (rad) at ω (rad/s).

    Returns (along, across, along_velocity): the coordinate along the blade (m), across it
    (m, +y toward the direction of rotation) and the velocity relative to the blade along it
    (m/s): u = (v − ω ẑ × p)·e_x.
    """
    x, y, vx, vy, theta = (np.asarray(a, dtype=float) for a in (x, y, vx, vy, theta))
    c, s = np.cos(theta), np.sin(theta)
    rel_x, rel_y = vx + omega * y, vy - omega * x
    return x * c + y * s, -x * s + y * c, rel_x * c + rel_y * s


def amplitude_left(
    t: ArrayLike, amplitude: ArrayLike, times: Sequence[float], start: float = 0.0
) -> FloatArray:
    """a(start + τ)/a(start) for each τ in ``times`` (s), linear interpolation in (t, a), -."""
    t, a = np.asarray(t, dtype=float), np.asarray(amplitude, dtype=float)
    a0 = np.interp(start, t, a)
    return np.interp(start + np.asarray(times, dtype=float), t, a) / a0


@dataclass(frozen=True)
class RateFit:
    """y(t) ≈ A·e^{λ t} + c fitted by least squares: λ (1/s) with its standard error."""

    rate: float
    rate_error: float
    amplitude: float
    offset: float
    rms: float
    """Root-mean-square residual, in the units of y."""


def fit_exponential(t: ArrayLike, y: ArrayLike) -> RateFit:
    """Fit y = A e^{λ(t − t0)} + c (t0 = t[0]); λ's standard error from the covariance.

    The start values come from the data alone: λ from a straight line through ln|dy/dt|
    (dy/dt = Aλe^{λt} has no offset), then A and c by linear least squares.
    """
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    if t.size < 5:
        raise ValueError(f"need at least 5 samples to fit a rate (got {t.size})")
    tau = t - t[0]
    slope = np.gradient(y, tau)
    usable = np.abs(slope) > 0
    lam0 = float(np.polyfit(tau[usable], np.log(np.abs(slope[usable])), 1)[0])
    basis = np.column_stack((np.exp(lam0 * tau), np.ones_like(tau)))
    (a0, c0), *_ = np.linalg.lstsq(basis, y, rcond=None)

    def model(tt: FloatArray, a: float, lam: float, c: float) -> FloatArray:
        return a * np.exp(lam * tt) + c

    (a, lam, c), cov = curve_fit(model, tau, y, p0=(a0, lam0, c0), maxfev=20000)
    residual = y - model(tau, a, lam, c)
    error = float(math.sqrt(cov[1, 1])) if np.isfinite(cov[1, 1]) else math.inf
    return RateFit(float(lam), error, float(a), float(c), float(np.sqrt(np.mean(residual**2))))


def free_flight(
    t: ArrayLike, position: ArrayLike, velocity: ArrayLike, deceleration: float
) -> FloatArray:
    """Positions (n, 2), m, of a point sliding over a stationary floor from ``position`` (m) with
    ``velocity`` (m/s) at t = 0, slowed by Coulomb friction a = f·g (m/s²) along its path:
    s(τ) = vτ − ½aτ² until it stops at τ = v/a. A straight line in the lab frame."""
    p0, v0 = np.asarray(position, dtype=float), np.asarray(velocity, dtype=float)
    speed = float(np.hypot(*v0))
    tau = np.asarray(t, dtype=float)
    if speed == 0:
        return np.tile(p0, (tau.size, 1))
    stop = speed / deceleration if deceleration > 0 else math.inf
    tau = np.clip(tau, 0.0, stop)
    path = speed * tau - 0.5 * deceleration * tau**2
    return p0 + np.outer(path, v0 / speed)
