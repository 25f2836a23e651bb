"""Soft contact laws as pure numba functions, and their per-material-pair parameter table.

Conventions shared by every soft-contact module (pairs here, walls in ``kernel``, hammer polygons
in ``polygons``): SI units, float64. A contact between body A and body B has the unit normal
``n`` pointing from B to A, the tangent ``t = ẑ × n = (−n_y, n_x)``, the overlap ``delta > 0``,
the approach rate ``ddelta = dδ/dt = −(v_A,c − v_B,c)·n`` and the tangential slip rate
``vt = (v_A,c − v_B,c)·t`` of A's contact point relative to B's. A disc of radius r centred at
x_A has its contact point at x_A − r n, whose velocity is v_A − r ω_A t (2-D: ω ẑ × (−r n)).

``contact_law`` returns the normal force ``fn`` (on A along +n, repulsive > 0), the tangential
force ``ft`` (on A along +t), the new tangential history and the energy the contact dissipated
over the step (``contact_force`` defines it); the caller applies
F = fn n + ft t to A at its contact point (torque −r_A ft on a disc), −F to B (torque −r_B ft on a
disc, ``r_B·(n × −F)``), and, if μ_r > 0, ``rolling_torque`` (+M on A, −M on B). In 2-D the
tangential spring history is a scalar ξ along the current tangent: storing it as a scalar *is*
the rotation of the spring onto the new tangent plane that 3-D codes do explicitly.

Parameter table ``params[mat_A, mat_B, :]`` (symmetric, float64, C-contiguous), columns P_*:

P_KN     normal stiffness k_n: N/m (linear) or (4/3)E*, Pa (Hertz: the contact's stiffness is
         k_n·√R*, R* = r_A r_B/(r_A + r_B) of the contact's own radii, r_A at a wall)
P_DAMP   dimensionless damping D: force D·√(k_n m_eff)·δ̇ (linear, D = 2ζ) or
         D·√(k_n m_eff)·δ^{1/4}·δ̇ (Hertz-Tsuji, D = α); m_eff is the contact's own reduced mass
         (m_A m_B/(m_A + m_B); a wall contact passes m_A, a hammer contact the hammer's
         effective mass), so e comes out right at walls and hammers too
P_KT     tangential stiffness: k_t in N/m (linear) or k_t = P_KT·√(R*δ) (Hertz; Mindlin-like)
P_DAMPT  tangential damping ratio ζ_t: force −2ζ_t √(k_t m_eff) v_t (default 0)
P_MU     Coulomb friction coefficient f: |F_t| ≤ f|F_n|; when exceeded, the spring is rescaled to
         the cap (ξ = −(F_t + c_t v_t)/k_t), Cundall & Strack (1979)
P_MUR    rolling-resistance coefficient μ_r (dimensionless): constant torque μ_r R_eff |F_n|
         opposing the relative rolling ω_A − ω_B (R_eff = r_A r_B/(r_A + r_B); r_A at a wall),
         limited so that it cannot reverse the rolling in one step (no chatter at rest)
P_HERTZ  0: linear spring-dashpot; 1: Hertz with Tsuji damping
P_CLAMP  1: force clamped at zero (F_n = max(0, …): contact ends when the force returns to 0,
         ``end="force"``); 0: attractive force allowed until the overlap returns to 0
         (``end="overlap"``). D must be calibrated for the same criterion.
"""

import math
from typing import Literal

import numpy as np
from numba import njit

from perga.analytic.contact import (
    HertzTsuji,
    LinearSpringDashpot,
    damping_ratio,
    tsuji_alpha,
)
from perga.geometry.disc_polygon import FASTMATH

P_KN, P_DAMP, P_KT, P_DAMPT, P_MU, P_MUR, P_HERTZ, P_CLAMP = range(8)
N_PARAMS = 8

DEFAULT_KT_RATIO = 2.0 / 7.0
"""Default k_t/k_n = 2/7: LAMMPS ``pair_style gran/hooke/history``'s k_t for k_t = NULL.

For spheres it equals the tangential and normal contact periods (tangential effective mass
m/(1 + m r²/I) = 2m/7). For discs (I = m r²/2) the period-matching ratio would be 1/3; 2/7 is
kept so that perga's runs are comparable with LAMMPS at the same inputs.
"""

Model = Literal["linear", "hertz"]
End = Literal["overlap", "force"]


@njit(cache=True, inline="always", fastmath=FASTMATH)
def touching(delta, ddelta, dt):
    """Whether a contact acts during the step: δ > 0 somewhere in [t − dt/2, t + dt/2].

    The kick of a step stands for the impulse over the interval [t − dt/2, t + dt/2] around the
    force evaluation (leapfrog form of symplectic Euler), so a contact is evaluated as soon as
    its overlap, extrapolated linearly, is positive anywhere in it: δ + ½ dt |δ̇| > 0.
    """
    return delta + 0.5 * dt * abs(ddelta) > 0.0


@njit(cache=True, inline="always", fastmath=FASTMATH)
def contact_force(kn, damp, hertz, clamp, kt, dampt, mu, delta, ddelta, vt, m_eff, xi, dt):
    """The soft contact law itself, from explicit coefficients (one row of the table, resolved).

    The single implementation of the normal and tangential law shared by granule pairs, walls
    (through ``contact_law``) and granule-polygon contacts
    (``perga.contact.soft.polygon_forces``, whose
    stiffness depends on the granule's radius under Hertz and so cannot come from the table).
    kn: normal stiffness, N/m (linear) or N/m^{3/2} (hertz != 0); damp: dimensionless damping D
    (2ζ linear, α Hertz-Tsuji); clamp != 0: F_n ≥ 0 (end="force"); kt: tangential stiffness at
    this overlap, N/m (the caller applies any √δ scaling); dampt: tangential damping ratio ζ_t;
    mu: friction coefficient. delta, ddelta, vt, m_eff, xi, dt and the returned
    (fn, ft, xi_new, dissipated): as in ``contact_law``.

    ddelta is the approach rate *at the force time t*: velocities of a kick-drift step are half a
    step old when forces are evaluated, so callers extrapolate them (the kernel by
    u = v + ½ dt a_prev, the polygon module by 1.5 δ̇_{n−1/2} − 0.5 δ̇_{n−3/2}); using the stale
    rate biases e by O(dt).

    The dashpot enters as its exact impulse over the kick interval: ∫ c(δ) δ̇ dt =
    D√(k_n m_eff)[Φ(δ⁺) − Φ(δ⁻)] with δ± = max(0, δ ± ½ dt δ̇), Φ(δ) = δ (linear) or
    (4/5) δ^{5/4} (Hertz), divided by dt. Inside a contact this equals the usual c(δ) δ̇ to
    O(dt²); at first touch it applies only the part of the step the bodies overlap, so that e
    does not depend on where in a step first touch falls (docs/validation.md).

    Dissipated energy over the step, J (< 0 only sliding with a dashpot above the cap, whose
    rescaled spring stores more than the work; docs/testing.md): normal (F_n − F_spring)·δ̇·dt
    (the dashpot's work, and the spring energy lost while F_n is clamped at 0) plus tangential
    −F_t v_t dt − ΔE_t (slip, damping, the spring's O(dt²) update), E_t (``tangential_force``).
    """
    fn, lost = normal_force(kn, damp, hertz, clamp, delta, ddelta, m_eff, dt)
    ft, xi, slip = tangential_force(kt, dampt, mu, fn, vt, m_eff, xi, dt, hertz)
    return fn, ft, xi, lost + slip


@njit(cache=True, inline="always", fastmath=FASTMATH)
def normal_force(kn, damp, hertz, clamp, delta, ddelta, m_eff, dt):
    """The normal half of ``contact_force`` (arguments as there): (fn, N; energy the dashpot
    dissipated over the step, and the spring's while F_n is clamped at 0, J)."""
    half = 0.5 * dt * ddelta
    hi = max(delta + half, 0.0)
    lo = max(delta - half, 0.0)
    d = max(delta, 0.0)
    if hertz != 0.0:
        spring = kn * d * math.sqrt(d)
        dphi = 0.8 * (hi * math.sqrt(math.sqrt(hi)) - lo * math.sqrt(math.sqrt(lo)))
        fn = spring + damp * math.sqrt(kn * m_eff) * dphi / dt
    else:
        spring = kn * d
        fn = spring + damp * math.sqrt(kn * m_eff) * (hi - lo) / dt
    if fn < 0.0 and clamp != 0.0:
        fn = 0.0
    return fn, (fn - spring) * ddelta * dt


@njit(cache=True, inline="always", fastmath=FASTMATH)
def tangential_force(kt, dampt, mu, fn, vt, m_eff, h, dt, hertz):
    """The tangential half of ``contact_force`` (arguments as there) for the normal force fn, N:
    (ft, N; the new spring history h; energy dissipated by slip, damping and the spring's
    update, J). For a frictionless undamped contact (mu = dampt = 0) it returns ft = 0, h = 0
    and the energy of the dropped spring: ``kernel.pair_force`` then skips it.

    The history h is the stretch ξ (m) of a linear spring, whose stored energy is ½ k_t ξ².
    A Hertz spring's k_t = P_KT √(R*δ) changes with the overlap, so its history is the energy
    coordinate h = ξ √k_t (stored energy ½ h², :func:`spring_energy`): the stretch is rescaled
    to each step's k_t, ξ = h/√k_t, so a change of overlap neither makes nor loses tangential
    energy, and where k_t = 0 (evaluated before the discs touch) nothing is stretched, stored
    or lost (docs/validation.md)."""
    if hertz != 0.0:
        if kt == 0.0:
            return 0.0, h, 0.0
        root = math.sqrt(kt)
        xi = h / root
    else:
        xi = h
    ct = 2.0 * dampt * math.sqrt(kt * m_eff) if dampt != 0.0 else 0.0
    stretched = xi + vt * dt
    ft = -kt * stretched - ct * vt
    cap = mu * abs(fn)
    if abs(ft) > cap:
        ft = math.copysign(cap, ft)
        slid = -(ft + ct * vt) / kt if kt > 0.0 else 0.0
        lost = -ft * vt * dt - 0.5 * kt * (slid * slid - xi * xi)
        xi = slid
    else:  # sticking: −F_t v_t dt − ½ k_t (ξ_new² − ξ²) in closed form
        lost = vt * vt * dt * (0.5 * kt * dt + ct)
        xi = stretched
    return ft, xi * root if hertz != 0.0 else xi, lost


@njit(cache=True, inline="always", fastmath=FASTMATH)
def spring_energy(kt, hertz, h):
    """Energy stored in a tangential spring of history h (``tangential_force``) and stiffness
    k_t (N/m), J: ½ k_t h² (linear, h the stretch) or ½ h² (Hertz, h the energy coordinate)."""
    return 0.5 * h * h if hertz != 0.0 else 0.5 * kt * h * h


@njit(cache=True, inline="always", fastmath=FASTMATH)
def contact_stiffness(params, a, b, r_eff):
    """Normal stiffness of a contact of materials a, b and effective radius r_eff (m): P_KN, N/m
    (linear), or P_KN·√r_eff, N/m^{3/2} (Hertz)."""
    kn = params[a, b, P_KN]
    if params[a, b, P_HERTZ] != 0.0:
        kn *= math.sqrt(r_eff)
    return kn


@njit(cache=True, inline="always", fastmath=FASTMATH)
def tangential_stiffness(params, a, b, r_eff, delta):
    """Tangential stiffness k_t (N/m) of materials a, b at effective radius r_eff and overlap
    delta (m): P_KT, or P_KT·√(r_eff·δ⁺) (Hertz)."""
    kt = params[a, b, P_KT]
    if params[a, b, P_HERTZ] != 0.0:
        kt *= math.sqrt(r_eff * max(delta, 0.0))
    return kt


@njit(cache=True, inline="always", fastmath=FASTMATH)
def released(params, a, b, r_eff, delta, h):
    """Energy of a tangential spring of history h (``tangential_force``) dropped when its
    contact ends at overlap delta, J.

    A contact ends (the history is reset) with h ≠ 0 only when the law left it so at its last
    step (tangential damping at F_n = 0, or an attractive F_n with end="overlap", or a Hertz
    spring still holding energy as its k_t went to 0); that energy then counts as dissipated.
    """
    kt = tangential_stiffness(params, a, b, r_eff, delta)
    return spring_energy(kt, params[a, b, P_HERTZ], h)


@njit(cache=True, inline="always", fastmath=FASTMATH)
def contact_law(params, a, b, r_eff, delta, ddelta, vt, m_eff, xi, dt):
    """Normal and tangential force of one contact between materials a, b over one step.

    Call when ``touching(delta, ddelta, dt)``. params: (n_mat, n_mat, N_PARAMS) table; r_eff:
    the contact's effective radius R*, m (Hertz stiffness, ``contact_stiffness``); delta:
    overlap at the step's time (may be ≤ 0 just before first touch), m; ddelta: approach rate
    dδ/dt at that time, m/s; vt: tangential slip rate of A's contact point relative to B's
    along t, m/s; m_eff: the contact's reduced mass, kg; xi: tangential spring elongation, m;
    dt: step, s. Returns (fn, ft, xi_new, dissipated): normal force on A along n (≥ 0 when
    clamped), N; tangential force on A along t, N; elongation after this step, m; energy the
    contact dissipated over the step, J.

    Reads the table row and calls ``contact_force`` (the law, its time discretisation and the
    dissipation are documented there); Hertz rows get the Mindlin-like k_t = P_KT·√(R*δ).
    """
    return contact_force(
        contact_stiffness(params, a, b, r_eff),
        params[a, b, P_DAMP],
        params[a, b, P_HERTZ],
        params[a, b, P_CLAMP],
        tangential_stiffness(params, a, b, r_eff, delta),
        params[a, b, P_DAMPT],
        params[a, b, P_MU],
        delta,
        ddelta,
        vt,
        m_eff,
        xi,
        dt,
    )


@njit(cache=True, inline="always", fastmath=FASTMATH)
def rolling_torque(params, a, b, fn, w_rel, r_eff, i_red, dt):
    """Rolling-resistance torque on A (−it on B), N·m.

    M = −sgn(w_rel)·min(μ_r R_eff |F_n|, |w_rel| I_red/dt).

    w_rel = ω_A − ω_B, rad/s; r_eff: rolling radius, m; i_red: reduced moment I_A I_B/(I_A + I_B)
    (I_A at a wall), kg·m². The cap |w_rel| I_red/dt stops the relative rolling in one step
    instead of reversing it (a constant-torque model otherwise chatters at rest).
    """
    mur = params[a, b, P_MUR]
    if mur == 0.0 or w_rel == 0.0:
        return 0.0
    torque = min(mur * r_eff * abs(fn), abs(w_rel) * i_red / dt)
    return -math.copysign(torque, w_rel)


def contact_parameters(
    model: Model,
    e: float,
    *,
    k_n: float | None = None,
    t_c: float | None = None,
    m_ref: float | None = None,
    friction: float = 0.5,
    rolling: float = 0.0,
    kt_ratio: float = DEFAULT_KT_RATIO,
    zeta_t: float = 0.0,
    end: End = "force",
) -> np.ndarray:
    """One row of the parameter table (N_PARAMS,) for a material pair, calibrated to restitution e.

    model: "linear" (F = k_n δ + 2ζ√(k_n m_eff) δ̇, ζ = ``damping_ratio(e, end)``) or "hertz"
    (F = k_n δ^{3/2} + α√(k_n m_eff) δ^{1/4} δ̇, α = ``tsuji_alpha(e, end)``, exact). Stiffness:
    k_n directly, or for "linear" from a contact duration t_c (s) on reduced mass m_ref (kg)
    (``LinearSpringDashpot.from_duration``). k_t = kt_ratio·k_n (Hertz: k_t = kt_ratio·k_n·√δ);
    friction f, rolling μ_r, tangential damping ratio zeta_t. end="force" (default) clamps
    F_n ≥ 0 and calibrates ζ for it (Schwager & Pöschel 2007; docs/validation.md);
    end="overlap" lets the force be attractive until δ = 0.
    """
    if model not in ("linear", "hertz"):
        raise ValueError(f"model must be 'linear' or 'hertz' (got {model!r})")
    if (k_n is None) == (t_c is None):
        raise ValueError("give exactly one of k_n and t_c")
    if t_c is not None:
        if model != "linear" or m_ref is None:
            raise ValueError("t_c needs model='linear' and m_ref (the reduced mass it refers to)")
        k_n = LinearSpringDashpot.from_duration(t_c, e, m_ref, end).k
    assert k_n is not None
    if not (k_n > 0.0 and math.isfinite(k_n)):
        raise ValueError(f"k_n must be > 0 (got {k_n})")
    for name, value in (("friction", friction), ("rolling", rolling), ("kt_ratio", kt_ratio)):
        if not value >= 0.0:
            raise ValueError(f"{name} must be >= 0 (got {value})")
    if not 0.0 <= zeta_t < 1.0:
        raise ValueError(f"zeta_t must be in [0, 1) (got {zeta_t})")
    row = np.zeros(N_PARAMS)
    row[P_KN] = k_n
    row[P_DAMP] = tsuji_alpha(e, end) if model == "hertz" else 2.0 * damping_ratio(e, end)
    row[P_KT] = kt_ratio * k_n
    row[P_DAMPT] = zeta_t
    row[P_MU] = friction
    row[P_MUR] = rolling
    row[P_HERTZ] = 1.0 if model == "hertz" else 0.0
    row[P_CLAMP] = 1.0 if end == "force" else 0.0
    return row


def pair_table(n_mat: int, rows: dict[tuple[int, int], np.ndarray]) -> np.ndarray:
    """Symmetric (n_mat, n_mat, N_PARAMS) table from rows keyed by material pairs (a, b).

    Every pair must be given (one of (a, b) and (b, a)); granule, wall and hammer materials share
    the table.
    """
    table = np.full((n_mat, n_mat, N_PARAMS), np.nan)
    for (a, b), row in rows.items():
        row = np.asarray(row, dtype=float)
        if row.shape != (N_PARAMS,):
            raise ValueError(f"row for {(a, b)} must have shape ({N_PARAMS},)")
        table[a, b] = row
        table[b, a] = row
    missing = [(a, b) for a in range(n_mat) for b in range(a, n_mat) if np.isnan(table[a, b]).any()]
    if missing:
        raise ValueError(f"material pairs without parameters: {missing}")
    return np.ascontiguousarray(table)


def uniform_table(row: np.ndarray, n_mat: int = 1) -> np.ndarray:
    """Table with the same row for every material pair."""
    return pair_table(n_mat, {(a, b): row for a in range(n_mat) for b in range(a, n_mat)})


def contact_duration(row: np.ndarray, m_eff: float, r_eff: float, v_max: float) -> float:
    """Duration of a head-on contact of reduced mass m_eff (kg) and effective radius r_eff (m)
    under ``row``, s.

    Linear: independent of speed and radius; Hertz (stiffness k_n√r_eff): at the approach speed
    v_max (m/s), the shortest over speeds up to v_max (t_c ∝ v^{-1/5}). Uses the closed forms
    of ``perga.analytic.contact``.
    """
    end: End = "force" if row[P_CLAMP] != 0.0 else "overlap"
    if row[P_HERTZ] != 0.0:
        k = row[P_KN] * math.sqrt(r_eff)
        return HertzTsuji(k, row[P_DAMP], m_eff, end).impact(v_max).duration
    return LinearSpringDashpot(row[P_KN], 0.5 * row[P_DAMP], m_eff, end).duration
