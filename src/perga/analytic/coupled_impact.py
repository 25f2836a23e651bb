"""The impact of a granule on a hammer at one contact point, with Coulomb friction, its sticking
cap and the hammer's effective mass as a full 2 × 2 matrix: hinged, free, or carried by a rotor
of prescribed motion.

Frame: n the hammer's outward normal at the contact (towards the granule), t = n turned +90°.
u = (u_n, u_t) is the granule's contact point's velocity relative to the hammer's material point
there (m/s; u_n < 0 approaching). An impulse J = J_n n + J_t t on the granule (−J on the hammer)
changes u by K·J, K = K_granule + K_hammer (m/(N·s)), the pair's compliance at the point
(Brach, Mechanical Impact Dynamics, 2007, ch. 4; Stronge, Impact Mechanics, 2000, ch. 2):

* a disc of mass m, radius r, moment I (touching at −r·n from its centre): K = diag(1/m,
  1/m + r²/I) (r²/I = 0 for a sliding point, I = inf);
* a body turning about a point A that moves as prescribed (a hinge on a rotor of prescribed
  speed), moment I_A about it, the contact at arm a from A: K = w wᵀ/I_A, w = (a⊥·n, a⊥·t),
  a⊥ = ẑ × a;
* a free body of mass M, moment I_C about its centre C, arm a from C: K = 𝟙/M + w wᵀ/I_C;
* a hammer welded to a rotor of prescribed motion: K = 0.

The law (Newton's restitution on the normal relative velocity, Coulomb's friction with the
sticking cap): u_n' = −e·u_n; the contact sticks (u_t' = 0) if that needs |J_t| <= f·J_n,
otherwise it slides with J_t = −s·f·J_n where s is the sign of u_t' (slip is not reversed by
friction). This is the linear complementarity problem an impulse solver such as Chipmunk's
converges to for one contact. Off-diagonal K (the arm not along n) couples the two: the normal
impulse changes the slip, and the friction changes the normal velocity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def granule_compliance(m: float, r: float, inertia: float) -> FloatArray:
    """K of a disc touching at −r·n from its centre: diag(1/m, 1/m + r²/I), m/(N·s); m in kg,
    r in m, inertia in kg·m² (math.inf: a sliding point)."""
    return np.diag([1.0 / m, 1.0 / m + (0.0 if math.isinf(inertia) else r * r / inertia)])


def _arm_weights(arm: ArrayLike, n: ArrayLike) -> FloatArray:
    """w = (a⊥·n, a⊥·t), a⊥ = ẑ × a, t = n turned +90° (m)."""
    a = np.asarray(arm, dtype=float)
    nx, ny = np.asarray(n, dtype=float)
    perp = np.array([-a[1], a[0]])
    return np.array([perp @ (nx, ny), perp @ (-ny, nx)])


def pivoted_compliance(moment: float, arm: ArrayLike, n: ArrayLike) -> FloatArray:
    """K of a body turning about a point of prescribed motion: w wᵀ/I_A (moment I_A in kg·m²
    about the point, arm from it to the contact in m, n the unit normal)."""
    w = _arm_weights(arm, n)
    return np.outer(w, w) / moment


def free_compliance(mass: float, moment: float, arm: ArrayLike, n: ArrayLike) -> FloatArray:
    """K of a free body: 𝟙/M + w wᵀ/I_C (mass M in kg, moment I_C about its centre of mass in
    kg·m², arm from the centre to the contact in m, n the unit normal)."""
    return np.eye(2) / mass + pivoted_compliance(moment, arm, n)


@dataclass(frozen=True)
class CoupledImpact:
    """The impulses of one impact and the relative velocity after it (frame of the module)."""

    normal_impulse: float
    """J_n >= 0 on the granule, N·s."""
    tangential_impulse: float
    """J_t on the granule along t, N·s."""
    normal_velocity: float
    """u_n' = −e·u_n, m/s."""
    tangential_velocity: float
    """u_t', m/s (0 when it sticks)."""
    sticks: bool
    """True if the slip is stopped with |J_t| <= f·J_n."""


def coupled_impact(u_n: float, u_t: float, e: float, f: float, K: ArrayLike) -> CoupledImpact:
    """Solve the module's law for one impact: u_n < 0 the approach (m/s), u_t the slip (m/s),
    e in [0, 1], f >= 0, K the pair's 2 × 2 compliance (m/(N·s), symmetric positive
    definite: a granule's own is, and a hammer's adds a positive semi-definite one)."""
    if not u_n < 0.0:
        raise ValueError(f"u_n must be < 0 m/s: an approach (got {u_n})")
    if not 0.0 <= e <= 1.0:
        raise ValueError(f"e must be in [0, 1] (got {e})")
    if not 0.0 <= f < math.inf:
        raise ValueError(f"f must be finite and >= 0 (got {f})")
    k = np.asarray(K, dtype=float)
    if k.shape != (2, 2) or not np.all(np.linalg.eigvalsh(0.5 * (k + k.T)) > 0.0):
        raise ValueError(f"K must be 2 x 2 and positive definite (got {k.tolist()})")
    target = -(1.0 + e) * u_n  # the change of u_n the restitution asks for
    j_n, j_t = np.linalg.solve(k, [target, -u_t])
    if j_n >= 0.0 and abs(j_t) <= f * j_n:
        return CoupledImpact(float(j_n), float(j_t), -e * u_n, 0.0, True)
    for s in (math.copysign(1.0, u_t), -math.copysign(1.0, u_t)):
        j_n = target / (k[0, 0] - s * f * k[0, 1])
        j_t = -s * f * j_n
        slip = u_t + k[1, 0] * j_n + k[1, 1] * j_t
        if j_n >= 0.0 and s * slip >= 0.0:
            return CoupledImpact(float(j_n), float(j_t), -e * u_n, float(slip), False)
    raise ValueError(f"no consistent sliding solution for u = ({u_n}, {u_t}), K = {k.tolist()}")
