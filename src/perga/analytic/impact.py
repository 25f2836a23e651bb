"""Rigid-body impact laws for a granule struck by a hammer (SI units throughout).

Every law here is instantaneous: the contact lasts so briefly that positions do not change,
finite forces (gravity, centrifugal, spring) give no impulse, and only the contact impulse and
the reactions of supports that are held fixed during the impact act. Restitution is Newton's
kinematic coefficient e (normal relative velocity after = −e × before), which is energetically
consistent for every law below because the normal and tangential directions are not coupled
by the mass matrices used.

Sign conventions: the unit normal n points from the hammer (the struck surface) to the granule;
in 2-D, a × b = a_x b_y − a_y b_x and ẑ × r = (−r_y, r_x); angular velocities are positive
counter-clockwise (about +ẑ).

Sources: Stronge, Impact Mechanics (2000); Brach, Mechanical Impact Dynamics, 2nd ed. (2007);
Goldsmith, Impact (1960).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perga.analytic.common import reduced_mass

FloatArray = NDArray[np.float64]
Vector2 = tuple[float, float]
GranuleShape = Literal["point", "disc", "sphere"]

_UNIT_NORMAL_TOLERANCE = 1e-9
"""Allowed deviation of |n| from 1, -: loose enough for normals built from cos/sin."""

_PARALLEL_AXIS_TOLERANCE = 1e-12
"""Relative round-off allowed in the check I_A >= M·|r_c|², -."""

_GYRATION_FACTOR: dict[str, float] = {"point": 0.0, "disc": 0.5, "sphere": 0.4}
"""I/(m r²) for each granule shape, -; 0 for 'point' marks a body that does not rotate."""


# --- argument checks -------------------------------------------------------------------------


def _check_mass(name: str, value: float, allow_inf: bool = False) -> None:
    if not (value > 0.0 and (allow_inf or math.isfinite(value))):
        allowed = "in (0, inf]" if allow_inf else "finite and > 0"
        raise ValueError(f"{name} must be {allowed} kg (got {value})")


def _check_hinge_inertia(I_A: float, M: float, arm_squared: float, arm: str) -> None:
    """I_A >= M·arm² (parallel-axis theorem), allowing round-off in arm²."""
    lower = M * arm_squared
    if not (lower * (1.0 - _PARALLEL_AXIS_TOLERANCE) <= I_A < math.inf and I_A > 0.0):
        raise ValueError(f"I_A must be in [M·{arm}², inf) = [{lower}, inf) kg·m², > 0 (got {I_A})")


def _gyration(shape: str) -> float:
    """I/(m r²) of the granule shape, -; 0 for 'point'."""
    if shape not in _GYRATION_FACTOR:
        raise ValueError(f"shape must be one of {sorted(_GYRATION_FACTOR)} (got {shape!r})")
    return _GYRATION_FACTOR[shape]


def _check_restitution(e: float) -> None:
    if not 0.0 <= e <= 1.0:
        raise ValueError(f"e must be in [0, 1] (got {e})")


def _check_finite(name: str, value: float, unit: str) -> None:
    if not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number of {unit} (got {value})")


def _vector(name: str, value: ArrayLike) -> FloatArray:
    vec = np.asarray(value, dtype=float)
    if vec.shape != (2,) or not np.all(np.isfinite(vec)):
        raise ValueError(f"{name} must be a finite 2-vector (got {value!r})")
    return vec


def _pair(vec: FloatArray) -> Vector2:
    return float(vec[0]), float(vec[1])


def _cross(a: FloatArray, b: FloatArray) -> float:
    """z-component of a × b for 2-vectors."""
    return float(a[0] * b[1] - a[1] * b[0])


def _z_cross(omega: float, r: FloatArray) -> FloatArray:
    """Ω ẑ × r, the velocity of point r of a body spinning at Ω about the origin."""
    return omega * np.array([-r[1], r[0]])


def _kinetic_energy(mass: float, speed_squared: float) -> float:
    """½·mass·speed², J; 0 for a body at rest even when its mass is infinite."""
    return 0.0 if speed_squared == 0.0 else 0.5 * mass * speed_squared


# --- 1. free two-body normal impact --------------------------------------------------------


@dataclass(frozen=True)
class NormalImpact:
    """Outcome of a central normal impact; velocities are components along n (m/s)."""

    granule_velocity: float
    """u_g, granule normal velocity after the impact, m/s."""
    hammer_velocity: float
    """u_h, hammer normal velocity after the impact, m/s."""
    impulse: float
    """J_n >= 0, normal impulse on the granule (along +n), N·s."""
    granule_energy_gain: float
    """½m(u_g² − v_g²), J (negative if the granule is slowed down)."""
    dissipated: float
    """½μ(1 − e²)w², J, w the approach speed; >= 0."""
    hammer_energy_before: float
    """½M v_h², J (normal part); ``math.inf`` for an infinite moving hammer, 0 if at rest."""


def normal_impact(m: float, M: float, v_granule: float, v_hammer: float, e: float) -> NormalImpact:
    """Free central impact of two point masses along the unit normal n (hammer → granule).

    With approach speed w = v_hammer − v_granule (m/s) and reduced mass μ = mM/(m + M) (kg):
    J_n = μ(1 + e)w (N·s), u_g = v_g + J_n/m, u_h = v_h − J_n/M, so u_g − u_h = e·w, and the
    energy dissipated is ½μ(1 − e²)w² (J). A granule at rest struck at speed V leaves at
    u_g = (1 + e)MV/(M + m) and the hammer continues at u_h = (M − em)V/(M + m).

    m: granule mass (kg, finite); M: hammer (effective) mass (kg, may be ``math.inf``: the
    hammer's velocity is then unchanged); e: Newton's restitution in [0, 1]. If w <= 0 the
    bodies are separating or grazing and nothing happens (zero impulse).

    Source: classical rigid-body impact (Newton's restitution); Stronge, Impact Mechanics
    (2000), ch. 2. Valid for rigid bodies, an impact much shorter than the motion, no friction,
    and a central (collinear) impact or a normal reduced to effective masses.
    """
    _check_mass("m", m)
    _check_mass("M", M, allow_inf=True)
    _check_finite("v_granule", v_granule, "m/s")
    _check_finite("v_hammer", v_hammer, "m/s")
    _check_restitution(e)
    mu = reduced_mass(m, M)
    approach = v_hammer - v_granule
    impulse = mu * (1.0 + e) * approach if approach > 0.0 else 0.0
    u_g = v_granule + impulse / m
    return NormalImpact(
        granule_velocity=u_g,
        hammer_velocity=v_hammer - impulse / M,
        impulse=impulse,
        granule_energy_gain=0.5 * m * (u_g**2 - v_granule**2),
        dissipated=0.5 * mu * (1.0 - e**2) * approach**2 if impulse > 0.0 else 0.0,
        hammer_energy_before=_kinetic_energy(M, v_hammer**2),
    )


# --- 2. hinged hammer ----------------------------------------------------------------------


def hinged_effective_mass(I_A: float, d: float) -> float:
    """Effective mass of a hinged hammer along an impact normal: M_eff = I_A/d² (kg).

    I_A: moment of inertia about the hinge (kg·m², > 0); d: lever arm of the normal about the
    hinge, d = (r_k × n)_z (m, any sign). d = 0 (normal through the hinge) gives ``math.inf``:
    the held hinge takes the whole impulse. Source: classical rigid-body impact; Stronge,
    Impact Mechanics (2000). Valid while the hinge is held fixed (or moves at a velocity the
    impact does not change) and the hammer is rigid.
    """
    if not 0.0 < I_A < math.inf:
        raise ValueError(f"I_A must be finite and > 0 kg·m² (got {I_A})")
    _check_finite("d", d, "m")
    d_squared = d * d  # may underflow to 0 for a tiny d: M_eff is then inf, as for d = 0
    return I_A / d_squared if d_squared > 0.0 else math.inf


def free_effective_mass(M: float, I_C: float, arm: float) -> float:
    """Smallest effective mass a free rigid body offers an impact at a point ``arm`` (m) from
    its centre of mass, along the normal perpendicular to the arm: M/(1 + M·arm²/I_C) (kg).

    M: mass (kg, > 0); I_C: moment of inertia about the centre of mass (kg·m², > 0). Source: the
    impulse-momentum relations of a free body, 1/M_eff = 1/M + (r × n)²/I_C (Stronge, Impact
    Mechanics (2000)), largest (r × n)² = arm²."""
    _check_mass("M", M)
    if not 0.0 < I_C < math.inf:
        raise ValueError(f"I_C must be finite and > 0 kg·m² (got {I_C})")
    _check_finite("arm", arm, "m")
    return M / (1.0 + M * arm**2 / I_C)


def centre_of_percussion(M: float, I_A: float, l_cg: float) -> float:
    """Distance from the hinge to the centre of percussion: q = I_A/(M·l_cg) (m).

    An impulse whose line of action is perpendicular to the hinge → centre-of-mass line and
    crosses it at q from the hinge produces no impulse at the hinge. M: hammer mass (kg);
    I_A: moment of inertia about the hinge (kg·m²), at least M·l_cg² (parallel-axis theorem);
    l_cg: hinge → centre-of-mass distance (m, > 0). q >= l_cg always. Source: classical
    rigid-body mechanics (Goldsmith, Impact (1960)). Valid for a rigid hammer.
    """
    _check_mass("M", M)
    if not 0.0 < l_cg < math.inf:
        raise ValueError(f"l_cg must be finite and > 0 m (got {l_cg})")
    _check_hinge_inertia(I_A, M, l_cg**2, "l_cg")
    return I_A / (M * l_cg)


@dataclass(frozen=True)
class HingedImpact:
    """Outcome of a frictionless impact of a hinged hammer on a free granule (lab frame)."""

    granule_velocity: Vector2
    """v_g', granule velocity after the impact, m/s."""
    angular_velocity: float
    """Ω', hammer absolute angular velocity after the impact, rad/s."""
    impulse: float
    """J >= 0, normal impulse on the granule (along +n), N·s."""
    hinge_impulse: Vector2
    """J_hinge = M·Δv_c + J·n, impulse of the hinge on the hammer, N·s."""
    effective_mass: float
    """M_eff = I_A/d², the hammer's effective mass along n, kg (inf if d = 0)."""
    granule_energy_gain: float
    """½m(|v_g'|² − |v_g|²), J."""
    dissipated: float
    """½μ(1 − e²)w² lost in the contact, J, μ = reduced mass of m and M_eff; >= 0."""
    hammer_energy_before: float
    """½M|v_c|² + ½I_cΩ², J, I_c = I_A − M|r_c|²."""
    hinge_work: float
    """J_hinge·v_A, work done on the hammer by the moving hinge (the rotor), J."""


def hinged_impact(
    *,
    M: float,
    I_A: float,
    r_c: ArrayLike,
    r_k: ArrayLike,
    n: ArrayLike,
    Omega: float,
    v_A: ArrayLike,
    m: float,
    v_g: ArrayLike,
    e: float,
) -> HingedImpact:
    """Frictionless impact of a hammer hinged at A on a free granule, general 2-D form.

    The pivot A is carried by a rotor of infinite inertia, so its velocity v_A (m/s) is
    unchanged by the impact. Contact-point velocity v_K = v_A + Ω ẑ × r_k; approach speed
    w = (v_K − v_g)·n; lever arm d = (r_k × n)_z; M_eff = I_A/d². Then (Stronge 2000)
    J = μ(1 + e)w with μ = m·M_eff/(m + M_eff), v_g' = v_g + (J/m)n, Ω' = Ω − J·d/I_A, and
    the hinge impulse follows from the hammer's linear momentum, M·Δv_c = −J n + J_hinge with
    Δv_c = ΔΩ ẑ × r_c. For a granule at rest, v_g' = (1 + e)·M_eff/(M_eff + m)·(v_K·n)n;
    J_hinge = 0 when n ⊥ r_c and the line of action crosses the centre-of-mass line at the
    centre of percussion (d = q, see :func:`centre_of_percussion`).

    Energy: ΔKE_granule + ΔKE_hammer = hinge_work − dissipated. The hinge is not passive when
    v_A ≠ 0: the rotor then feeds (or absorbs) J_hinge·v_A, so the total kinetic energy can
    grow; with v_A = 0 it never does. Angular momentum about A is conserved.

    M: hammer mass (kg); I_A: moment of inertia about the hinge (kg·m², >= M|r_c|²);
    r_c, r_k: hinge → centre of mass and hinge → contact point (m); n: unit normal from hammer
    to granule; Omega: hammer absolute angular velocity (rad/s); m, v_g: granule mass (kg) and
    velocity (m/s); e: restitution in [0, 1]. No impulse if w <= 0.

    Source: classical rigid-body impact; Stronge, Impact Mechanics (2000). Valid for a rigid,
    frictionless, instantaneous impact with the granule's centre on the line of the impulse.
    """
    _check_mass("M", M)
    rc, rk, nv, vA, vg = (
        _vector(name, value)
        for name, value in (("r_c", r_c), ("r_k", r_k), ("n", n), ("v_A", v_A), ("v_g", v_g))
    )
    norm = float(np.hypot(nv[0], nv[1]))
    if abs(norm - 1.0) > _UNIT_NORMAL_TOLERANCE:
        raise ValueError(f"n must be a unit vector, |n| = 1 ± 1e-9 (got |n| = {norm})")
    rc2 = float(rc @ rc)
    _check_hinge_inertia(I_A, M, rc2, "|r_c|")
    _check_finite("Omega", Omega, "rad/s")
    d = _cross(rk, nv)
    M_eff = hinged_effective_mass(I_A, d)
    v_K = vA + _z_cross(Omega, rk)
    normal = normal_impact(m, M_eff, float(vg @ nv), float(v_K @ nv), e)
    J = normal.impulse
    delta_omega = -J * d / I_A
    vg_after = vg + (J / m) * nv
    v_c = vA + _z_cross(Omega, rc)
    hinge = M * _z_cross(delta_omega, rc) + J * nv
    I_c = max(I_A - M * rc2, 0.0)
    return HingedImpact(
        granule_velocity=_pair(vg_after),
        angular_velocity=Omega + delta_omega,
        impulse=J,
        hinge_impulse=_pair(hinge),
        effective_mass=M_eff,
        granule_energy_gain=0.5 * m * float(vg_after @ vg_after - vg @ vg),
        dissipated=normal.dissipated,
        hammer_energy_before=0.5 * M * float(v_c @ v_c) + 0.5 * I_c * Omega**2,
        hinge_work=float(hinge @ vA),
    )


# --- 3. oblique impact with Coulomb friction ------------------------------------------------


def slip_factor(shape: GranuleShape) -> float:
    """k = 1 + m r²/I, the factor by which rotation softens the granule tangentially (-).

    'point' (no rotation): 1; 'disc' (I = m r²/2): 3; 'sphere' (I = 2/5 m r²): 7/2. Against
    an immovable surface the tangential impulse that stops slip s is m·s/k. Source: Stronge,
    Impact Mechanics (2000). Valid for homogeneous bodies.
    """
    gyration = _gyration(shape)
    return 1.0 if gyration == 0.0 else 1.0 + 1.0 / gyration


@dataclass(frozen=True)
class ObliqueImpact:
    """Outcome of an oblique impact on a surface, in the surface's pre-impact frame."""

    normal_velocity: float
    """v_n', granule centre normal velocity after, m/s (> 0 leaving the surface)."""
    tangential_velocity: float
    """v_t', granule centre tangential velocity after, m/s."""
    spin: float
    """ω_g', granule spin after, rad/s (counter-clockwise positive)."""
    normal_impulse: float
    """J_n >= 0 on the granule, N·s."""
    tangential_impulse: float
    """J_t on the granule along t, N·s; opposite in sign to the slip."""
    sticks: bool
    """True if the slip is brought to zero (the Coulomb cap f·J_n is not reached)."""
    slip_before: float
    """s = v_t + r·ω_g, contact-point slip relative to the surface, m/s."""
    slip_after: float
    """s' = v_t' + r·ω_g' + J_t/M_t, m/s: same sign as s, or zero when sticking."""
    energy_before: float
    """½m(v_n² + v_t²) + ½Iω_g², granule KE before, J."""
    energy_after: float
    """Granule KE after, J."""
    dissipated: float
    """energy_before − energy_after − ½(J_n²/M_n + J_t²/M_t), J; >= 0."""


def oblique_impact(
    m: float,
    r: float,
    v_n: float,
    v_t: float,
    e: float,
    f: float,
    *,
    shape: GranuleShape = "disc",
    omega_g: float = 0.0,
    M_n: float = math.inf,
    M_t: float = math.inf,
) -> ObliqueImpact:
    """Oblique impact of a granule on a hammer surface with Coulomb friction and a sticking cap.

    Frame: the struck surface's contact point at rest before the impact, unit normal n out of
    the surface towards the granule, unit tangent t with t × n = ẑ (n = ŷ gives t = x̂). The
    granule's contact point is at −r·n from its centre, so its slip is s = v_t + r·ω_g (m/s).

    J_n = (1 + e)|v_n|/(1/m + 1/M_n) (N·s), v_n' = v_n + J_n/m;
    J_t = −sgn(s)·min(f·J_n, |s|/(1/m + r²/I + 1/M_t)) (N·s, r²/I = 0 for 'point'),
    v_t' = v_t + J_t/m, ω_g' = ω_g + r·J_t/I.
    The contact sticks (slip stopped, cap inactive) iff |s| <= f·J_n·(1/m + r²/I + 1/M_t); with
    M_n = M_t = inf this is |s| <= k·f·(1 + e)|v_n|, k = :func:`slip_factor`. Because the
    cap never reverses the slip, the tangential impulse only removes energy; the normal part
    removes ½μ_n(1 − e²)v_n².

    m: granule mass (kg); r: radius (m, > 0; >= 0 for 'point'); v_n: normal velocity (m/s,
    < 0 approaching; no impact otherwise, and then ``sticks`` is False); v_t: tangential
    velocity (m/s); omega_g: spin (rad/s, must be 0 for 'point'); e: restitution in [0, 1];
    f: friction coefficient >= 0; M_n, M_t: effective masses of the struck body along n and t
    (kg, default ``math.inf``: an immovable surface).

    Source: Brach, Mechanical Impact Dynamics (2007) (impulse-ratio model with the critical
    ratio); Stronge, Impact Mechanics (2000). Valid for a rigid granule on a flat surface whose
    normal and tangential responses are uncoupled (diagonal effective-mass matrix); then slip
    either stops or keeps its direction during the impact, and this algebraic law agrees with
    Stronge's incremental analysis. Tangential compliance (rebound of stored tangential
    strain, slip reversal) is not modelled.
    """
    gyration = _gyration(shape)
    _check_mass("m", m)
    _check_mass("M_n", M_n, allow_inf=True)
    _check_mass("M_t", M_t, allow_inf=True)
    min_radius = "finite and >= 0" if shape == "point" else "finite and > 0"
    if not (0.0 <= r < math.inf and (r > 0.0 or shape == "point")):
        raise ValueError(f"r must be {min_radius} m for shape {shape!r} (got {r})")
    _check_finite("v_n", v_n, "m/s")
    _check_finite("v_t", v_t, "m/s")
    _check_finite("omega_g", omega_g, "rad/s")
    if shape == "point" and omega_g != 0.0:
        raise ValueError(f"omega_g must be 0 rad/s for shape 'point' (got {omega_g})")
    if not 0.0 <= f < math.inf:
        raise ValueError(f"f must be finite and >= 0 (got {f})")

    inertia = gyration * m * r**2
    spin_per_impulse = 0.0 if gyration == 0.0 else 1.0 / (gyration * m * r)  # r/I, 1/(kg·m)
    slip = v_t + r * omega_g
    normal = normal_impact(m, M_n, v_n, 0.0, e)
    J_n = normal.impulse
    tangential_compliance = 1.0 / m + r * spin_per_impulse + 1.0 / M_t
    sticking_impulse = abs(slip) / tangential_compliance
    sticks = J_n > 0.0 and sticking_impulse <= f * J_n
    J_t = -math.copysign(min(f * J_n, sticking_impulse), slip)
    v_t_after = v_t + J_t / m
    omega_after = omega_g + J_t * spin_per_impulse
    v_n_after = normal.granule_velocity
    energy_before = 0.5 * (m * (v_n**2 + v_t**2) + inertia * omega_g**2)
    energy_after = 0.5 * (m * (v_n_after**2 + v_t_after**2) + inertia * omega_after**2)
    return ObliqueImpact(
        normal_velocity=v_n_after,
        tangential_velocity=v_t_after,
        spin=omega_after,
        normal_impulse=J_n,
        tangential_impulse=J_t,
        sticks=sticks,
        slip_before=slip,
        slip_after=v_t_after + r * omega_after + J_t / M_t,
        energy_before=energy_before,
        energy_after=energy_after,
        dissipated=energy_before - energy_after - 0.5 * (J_n**2 / M_n + J_t**2 / M_t),
    )


# --- 4. energy bookkeeping and efficiencies ------------------------------------------------


@dataclass(frozen=True)
class ImpactEfficiencies:
    """Four dimensionless energy ratios of one normal impact (granule at rest, free hammer)."""

    transfer: float
    """Granule KE gained / hammer KE before = (1 + e)²mM/(M + m)², -; at most 1."""
    relative: float
    """Granule KE gained / ½μV² = (1 + e)²M/(M + m), -; up to 4, not bounded by 1."""
    dissipated: float
    """Energy dissipated / hammer KE before = (1 − e²)m/(M + m), -."""
    hammer_frame_loss: float
    """Fraction of the relative-motion KE ½μw² lost = 1 − e², -."""


def impact_efficiencies(m: float, M: float, e: float) -> ImpactEfficiencies:
    """Energy ratios ("efficiencies") of a granule at rest struck by a free hammer, side by side.

    Granule mass m (kg), hammer mass M (kg, may be ``math.inf``), striking speed V (the ratios
    do not depend on it), restitution e in [0, 1], μ = mM/(m + M):
    transfer = (1 + e)²mM/(M + m)²; relative = (1 + e)²M/(M + m);
    dissipated = (1 − e²)m/(M + m); hammer_frame_loss = 1 − e².

    hammer_frame_loss is the granule's fractional KE loss seen from the hammer only in the
    limit M → ∞; for finite M that fraction, in the hammer's pre-impact frame, is
    1 − ((eM − m)/(M + m))², whereas 1 − e² is exact for the KE of relative motion.

    For m ≪ M the ratios normalised by the hammer's energy, transfer ≈ (1 + e)²m/M and
    dissipated ≈ (1 − e²)m/M, scale like 1/M (a heavy hammer wastes its energy by keeping
    it); those normalised by the relative motion do not: relative → (1 + e)² and
    hammer_frame_loss = 1 − e² whatever M is.

    Source: classical rigid-body impact; Stronge, Impact Mechanics (2000). Valid as
    :func:`normal_impact` (central, frictionless, rigid).
    """
    _check_mass("m", m)
    _check_mass("M", M, allow_inf=True)
    _check_restitution(e)
    ratio = m / M  # 0 for an infinite hammer: every formula below then takes its limit
    return ImpactEfficiencies(
        transfer=(1.0 + e) ** 2 * ratio / (1.0 + ratio) ** 2,
        relative=(1.0 + e) ** 2 / (1.0 + ratio),
        dissipated=(1.0 - e**2) * ratio / (1.0 + ratio),
        hammer_frame_loss=1.0 - e**2,
    )


def paper_energy_change(m: float, v0: ArrayLike, v1: ArrayLike) -> float:
    """Eq. (60) of Syromiatnykov, Bielykh & Kharchenko (2026): ΔE = ½m(|v0|² − |v1|²) (J).

    m: granule mass (kg); v0, v1: granule velocity before and after the impact (m/s, scalars
    or vectors of the same length). Positive when the granule loses energy. It is the
    granule's own KE change, frame-dependent, and equals the energy dissipated only against
    an immovable surface (M = inf) in that surface's frame.
    """
    _check_mass("m", m)
    a = np.atleast_1d(np.asarray(v0, dtype=float))
    b = np.atleast_1d(np.asarray(v1, dtype=float))
    if a.shape != b.shape or a.ndim != 1 or not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        raise ValueError(f"v0 and v1 must be finite vectors of one length (got {v0!r}, {v1!r})")
    return 0.5 * m * float(a @ a - b @ b)
