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

Parameter table ``params[mat_A, mat_B, :]`` (symmetric, float64, C-contiguous): one row per
material pair, made by its contact law (:meth:`perga.contact.laws.base.ContactLaw.row`), its
columns P_* and normal-force forms in :mod:`perga.contact.laws.row`.
"""

import math

import numpy as np
from numba import njit

from perga.analytic.contact import End, HertzTsuji, LinearSpringDashpot
from perga.contact.laws import contact_law as named_law
from perga.contact.laws.row import (
    LINEAR,
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
from perga.geometry.disc_polygon import FASTMATH


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
    does not depend on where in a step first touch falls (docs/dev/validation.md).

    Dissipated energy over the step, J (< 0 only sliding with a dashpot above the cap, whose
    rescaled spring stores more than the work; docs/dev/testing.md): normal (F_n − F_spring)·δ̇·dt
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
    or lost (docs/dev/validation.md)."""
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
def form(params, a, b, linear):
    """The normal-force form (P_HERTZ) of row a, b; LINEAR without reading it where ``linear``
    (the caller knows the table holds linear rows only): with ``linear`` a constant of the
    compiled code, the compiler drops every Hertz branch of the law (docs/dev/performance.md)."""
    return float(LINEAR) if linear else params[a, b, P_HERTZ]


@njit(cache=True, inline="always", fastmath=FASTMATH)
def contact_stiffness(params, a, b, r_eff, hertz):
    """Normal stiffness of a contact of materials a, b and effective radius r_eff (m) whose row
    has the form hertz (``form``): P_KN, N/m (linear), or P_KN·√r_eff, N/m^{3/2} (Hertz)."""
    kn = params[a, b, P_KN]
    if hertz != 0.0:
        kn *= math.sqrt(r_eff)
    return kn


@njit(cache=True, inline="always", fastmath=FASTMATH)
def tangential_stiffness(params, a, b, r_eff, delta, hertz):
    """Tangential stiffness k_t (N/m) of materials a, b at effective radius r_eff and overlap
    delta (m) for the row's form hertz (``form``): P_KT, or P_KT·√(r_eff·δ⁺) (Hertz)."""
    kt = params[a, b, P_KT]
    if hertz != 0.0:
        kt *= math.sqrt(r_eff * max(delta, 0.0))
    return kt


@njit(cache=True, inline="always", fastmath=FASTMATH)
def released(params, a, b, r_eff, delta, h, hertz):
    """Energy of a tangential spring of history h (``tangential_force``) dropped when its
    contact ends at overlap delta, J; hertz: the row's form (``form``).

    A contact ends (the history is reset) with h ≠ 0 only when the law left it so at its last
    step (tangential damping at F_n = 0, or an attractive F_n with end="overlap", or a Hertz
    spring still holding energy as its k_t went to 0); that energy then counts as dissipated.
    """
    return spring_energy(tangential_stiffness(params, a, b, r_eff, delta, hertz), hertz, h)


@njit(cache=True, inline="always", fastmath=FASTMATH)
def contact_law(params, a, b, hertz, r_eff, delta, ddelta, vt, m_eff, xi, dt):
    """Normal and tangential force of one contact between materials a, b over one step.

    Call when ``touching(delta, ddelta, dt)``. params: (n_mat, n_mat, N_PARAMS) table; hertz:
    the row's normal-force form (``form``); r_eff:
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
        contact_stiffness(params, a, b, r_eff, hertz),
        params[a, b, P_DAMP],
        hertz,
        params[a, b, P_CLAMP],
        tangential_stiffness(params, a, b, r_eff, delta, hertz),
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
    law: str,
    e: float,
    *,
    k_n: float | None = None,
    t_c: float | None = None,
    m_ref: float | None = None,
    friction: float = 0.5,
    rolling: float = 0.0,
    kt_ratio: float | None = None,
    zeta_t: float = 0.0,
    end: End = "force",
) -> np.ndarray:
    """One row of the parameter table (N_PARAMS,) for a material pair, calibrated to restitution e.

    law: a contact law's name (:data:`perga.contact.laws.LAWS`), e.g. "linear"
    (F = k_n δ + 2ζ√(k_n m_eff) δ̇) or "hertz" (F = k_n δ^{3/2} + α√(k_n m_eff) δ^{1/4} δ̇), whose
    row it is (:meth:`~perga.contact.laws.base.ContactLaw.row`). Stiffness: k_n directly, or
    from a contact duration t_c (s) on reduced mass m_ref (kg) for a law whose duration the
    mass fixes (``fixed_duration``; linear: ``LinearSpringDashpot.from_duration``).
    k_t = kt_ratio·k_n (Hertz: k_t = kt_ratio·k_n·√δ; default the law's, 2/7); friction f,
    rolling μ_r, tangential damping ratio zeta_t. end="force" (default) clamps F_n ≥ 0 and
    calibrates the damping for it (Schwager & Pöschel 2007; docs/dev/validation.md); end="overlap"
    lets the force be attractive until δ = 0.
    """
    contact = named_law(law)
    if (k_n is None) == (t_c is None):
        raise ValueError("give exactly one of k_n and t_c")
    if t_c is not None:
        if not contact.fixed_duration or m_ref is None:
            raise ValueError(
                "t_c needs a law whose duration the mass fixes (linear) and m_ref (the reduced "
                "mass it refers to)"
            )
        k_n = contact.stiffness_for_duration(t_c, e, m_ref, math.nan, math.nan, end)
    assert k_n is not None
    if kt_ratio is None:
        kt_ratio = contact.default_tangential_ratio
    if not (k_n > 0.0 and math.isfinite(k_n)):
        raise ValueError(f"k_n must be > 0 (got {k_n})")
    for name, value in (("friction", friction), ("rolling", rolling), ("kt_ratio", kt_ratio)):
        if not value >= 0.0:
            raise ValueError(f"{name} must be >= 0 (got {value})")
    if not 0.0 <= zeta_t < 1.0:
        raise ValueError(f"zeta_t must be in [0, 1) (got {zeta_t})")
    return contact.row(
        e, k_n, friction=friction, rolling=rolling, kt_ratio=kt_ratio, zeta_t=zeta_t, end=end
    )


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

    By the row's normal-force form, whatever law made it (:mod:`perga.contact.laws.row`):
    linear, independent of speed and radius; Hertz (stiffness k_n√r_eff), at the approach speed
    v_max (m/s), the shortest over speeds up to v_max (t_c ∝ v^{-1/5}). Uses the closed forms
    of ``perga.analytic.contact``.
    """
    end: End = "force" if row[P_CLAMP] != 0.0 else "overlap"
    if row[P_HERTZ] != 0.0:
        k = row[P_KN] * math.sqrt(r_eff)
        return HertzTsuji(k, row[P_DAMP], m_eff, end).impact(v_max).duration
    return LinearSpringDashpot(row[P_KN], 0.5 * row[P_DAMP], m_eff, end).duration
