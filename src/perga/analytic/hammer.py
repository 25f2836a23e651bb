"""Hammer kinematics (paper eq. 41-54), a plate hammer's mass properties, and the hinged hammer
in the centrifugal field.

Frames: O is the rotor axis, OXY fixed. The hinge A sits at radius R and turns with the rotor
angle φ(t); the hammer axis makes the angle α(t) with the radial line through A. C is the
hammer's centre of mass at distance L from A along the axis, K a point of the hammer at
distance a from A along the axis. Units: m, rad, s, kg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import ellipk

FloatArray = NDArray[np.float64]
Vector = tuple[FloatArray, FloatArray]


def _unit(angle: ArrayLike) -> Vector:
    angle = np.asarray(angle, dtype=float)
    return np.cos(angle), np.sin(angle)


def pivot_position(R: float, phi: ArrayLike) -> Vector:
    """Eq. (43): r_A = R(cos φ, sin φ), m."""
    c, s = _unit(phi)
    return R * c, R * s


def pivot_velocity(R: float, phi: ArrayLike, phi_dot: ArrayLike) -> Vector:
    """Eq. (44): ṙ_A = Rφ̇(−sin φ, cos φ), m/s."""
    c, s = _unit(phi)
    phi_dot = np.asarray(phi_dot, dtype=float)
    return -R * phi_dot * s, R * phi_dot * c


def pivot_acceleration(R: float, phi: ArrayLike, phi_dot: ArrayLike, phi_ddot: ArrayLike) -> Vector:
    """Eq. (45): r̈_A = Rφ̈(−sin φ, cos φ) − Rφ̇²(cos φ, sin φ), m/s²."""
    c, s = _unit(phi)
    w, wd = np.asarray(phi_dot, dtype=float), np.asarray(phi_ddot, dtype=float)
    return -R * wd * s - R * w**2 * c, R * wd * c - R * w**2 * s


def point_on_hammer_position(R: float, arm: float, phi: ArrayLike, alpha: ArrayLike) -> Vector:
    """Eq. (46) with arm = L (centre of mass C), eq. (49)-(50) with arm = a (contact point K), m."""
    ax, ay = pivot_position(R, phi)
    c, s = _unit(np.asarray(phi) + np.asarray(alpha))
    return ax + arm * c, ay + arm * s


def point_on_hammer_velocity(
    R: float,
    arm: float,
    phi: ArrayLike,
    alpha: ArrayLike,
    phi_dot: ArrayLike,
    alpha_dot: ArrayLike,
) -> Vector:
    """Eq. (47) (arm = L) and eq. (51) (arm = a): ṙ = ṙ_A + arm(φ̇ + α̇)(−sin(φ+α), cos(φ+α)), m/s."""
    vx, vy = pivot_velocity(R, phi, phi_dot)
    c, s = _unit(np.asarray(phi) + np.asarray(alpha))
    spin = np.asarray(phi_dot, dtype=float) + np.asarray(alpha_dot, dtype=float)
    return vx - arm * spin * s, vy + arm * spin * c


def centre_of_mass_speed_squared(
    R: float, L: float, alpha: ArrayLike, phi_dot: ArrayLike, alpha_dot: ArrayLike
) -> FloatArray:
    """Eq. (48): v_C² = R²φ̇² + L²(φ̇+α̇)² + 2RLφ̇(φ̇+α̇)cos α, m²/s²."""
    w = np.asarray(phi_dot, dtype=float)
    spin = w + np.asarray(alpha_dot, dtype=float)
    return R**2 * w**2 + L**2 * spin**2 + 2 * R * L * w * spin * np.cos(alpha)


NormalChoice = Literal["paper", "face"]


def contact_velocity_components(
    R: float,
    a: float,
    phi: ArrayLike,
    alpha: ArrayLike,
    phi_dot: ArrayLike,
    alpha_dot: ArrayLike,
    normal: NormalChoice = "paper",
) -> tuple[FloatArray, FloatArray]:
    """Eq. (53)-(54): normal and tangential velocity of the contact point K, m/s.

    ``normal="paper"`` takes n along the hammer axis, n = (cos(φ+α), sin(φ+α)) as printed in
    eq. (53); then v_Kn = Rφ̇ sin α, which is zero for a radial hammer (α = 0): the paper's
    normal sees no impact at all. ``normal="face"`` takes the striking face's normal,
    perpendicular to the axis and pointing in the direction of rotation (the paper's τ); then
    v_Kn = Rφ̇ cos α + a(φ̇ + α̇), the speed with which a radial hammer's face meets a granule.
    Returns (v_n, v_t) in the chosen (n, t) basis, t = n rotated by +90°.
    """
    vx, vy = point_on_hammer_velocity(R, a, phi, alpha, phi_dot, alpha_dot)
    theta = np.asarray(phi, dtype=float) + np.asarray(alpha, dtype=float)
    if normal == "face":
        theta = theta + math.pi / 2
    elif normal != "paper":
        raise ValueError(f"normal must be 'paper' or 'face' (got {normal!r})")
    nx, ny = _unit(theta)
    return vx * nx + vy * ny, -vx * ny + vy * nx


@dataclass(frozen=True)
class PlateHammer:
    """A rectangular plate hammer hinged on a hole on its axis (the hole's mass is neglected).

    length (m) along the axis, width (m) across it, thickness (m) out of plane, density
    (kg/m³), hinge_offset (m) from the inner end to the hinge. Mass M = ρ·length·width·thickness;
    centre of mass at l_cg = length/2 − hinge_offset from the hinge; I_C = M(length² + width²)/12
    about the centre of mass; I_A = I_C + M·l_cg² about the hinge (parallel-axis theorem).
    """

    length: float
    width: float
    thickness: float
    density: float
    hinge_offset: float

    def __post_init__(self) -> None:
        for name in ("length", "width", "thickness", "density"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} must be > 0 (got {getattr(self, name)})")
        if not 0 <= self.hinge_offset < self.length / 2:
            raise ValueError(
                f"hinge_offset must be in [0, length/2) = [0, {self.length / 2}) m "
                f"(got {self.hinge_offset})"
            )

    @property
    def mass(self) -> float:
        """M, kg."""
        return self.density * self.length * self.width * self.thickness

    @property
    def hinge_to_centre_of_mass(self) -> float:
        """l_cg, m."""
        return self.length / 2 - self.hinge_offset

    @property
    def inertia_about_centre(self) -> float:
        """I_C, kg·m²."""
        return self.mass * (self.length**2 + self.width**2) / 12

    @property
    def inertia_about_hinge(self) -> float:
        """I_A, kg·m²."""
        return self.inertia_about_centre + self.mass * self.hinge_to_centre_of_mass**2

    @property
    def tip_distance(self) -> float:
        """Distance from the hinge to the outer end, m."""
        return self.length - self.hinge_offset

    def with_mass(self, mass: float) -> PlateHammer:
        """The same outline with the thickness scaled to give ``mass`` (kg)."""
        return PlateHammer(
            self.length,
            self.width,
            self.thickness * mass / self.mass,
            self.density,
            self.hinge_offset,
        )


def swing_frequency(omega: float, M: float, R: float, l_cg: float, I_A: float) -> float:
    """Small-swing angular frequency of a hinged hammer in the centrifugal field, rad/s.

    Ω = ω·√(M R l_cg / I_A), from I_A α̈ = −M ω² R l_cg sin α (see :func:`swing_acceleration`).
    Stable equilibrium α = 0 (hammer pointing radially outward), unstable α = π. Valid at
    constant ω, in the plane of rotation, with no hinge friction and no gravity in the plane.
    """
    if not (omega > 0 and M > 0 and R > 0 and l_cg > 0 and I_A > 0):
        raise ValueError(
            f"omega, M, R, l_cg and I_A must be > 0 (got {omega}, {M}, {R}, {l_cg}, {I_A})"
        )
    return omega * math.sqrt(M * R * l_cg / I_A)


def swing_acceleration(
    alpha: ArrayLike, omega: float, M: float, R: float, l_cg: float, I_A: float
) -> FloatArray:
    """α̈ = −(M ω² R l_cg / I_A)·sin α, rad/s² (rotating frame; Coriolis forces on the hammer
    act along lines through the hinge and give no torque about it)."""
    return -(M * omega**2 * R * l_cg / I_A) * np.sin(np.asarray(alpha, dtype=float))


def swing_period(
    amplitude: float, omega: float, M: float, R: float, l_cg: float, I_A: float
) -> float:
    """Period of a swing of amplitude α0 < π, s: T = 4·K(sin²(α0/2))/Ω (pendulum, exact).

    K is the complete elliptic integral of the first kind with parameter m = k²; as α0 → 0,
    T → 2π/Ω.
    """
    if not 0 <= amplitude < math.pi:
        raise ValueError(f"amplitude must be in [0, π) rad (got {amplitude})")
    big_omega = swing_frequency(omega, M, R, l_cg, I_A)
    return 4.0 * float(ellipk(math.sin(amplitude / 2) ** 2)) / big_omega
