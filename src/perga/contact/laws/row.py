"""What a contact law hands the soft kernel: the columns of its pair table and the normal-force
forms it integrates (SI units, float64).

Pair table ``params[mat_A, mat_B, :]`` (symmetric, C-contiguous; :mod:`perga.contact.soft.laws`
builds and reads it), columns P_*:

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
P_HERTZ  the normal-force form: LINEAR (0) or HERTZ (1)
P_CLAMP  1: force clamped at zero (F_n = max(0, …): contact ends when the force returns to 0,
         ``end="force"``); 0: attractive force allowed until the overlap returns to 0
         (``end="overlap"``). D must be calibrated for the same criterion.
"""

P_KN, P_DAMP, P_KT, P_DAMPT, P_MU, P_MUR, P_HERTZ, P_CLAMP = range(8)
N_PARAMS = 8

LINEAR = 0
"""Normal-force form: linear spring-dashpot F = k_n δ + c δ̇ (Cundall & Strack 1979)."""
HERTZ = 1
"""Normal-force form: Hertz with Tsuji damping F = k δ^{3/2} + α√(m k) δ^{1/4} δ̇, k = k_n√R*
(Tsuji et al. 1992)."""
