"""Issue 19, item 3: oblique impacts of the issue's granule (E = 5 MPa, ν = 0.35, r = 3 mm,
f = 0.3, 3.9 m/s) on a rigid wall in Maw, Barber & Fawcett's coordinates, Ψ = κ s/(f v_n)
(``tests/contact/soft/test_mindlin.py``): Ψ2 against Ψ1 for k_t/k_n = 2/7 and Mindlin's 1.18,
the model's reference (solve_ivp) beside the kernel at the plan's step (50 per tangential
half-period or per contact, the shorter), with MBF's gross-slip line Ψ1 − 3κ(1 + e).

Then the full-stick limit (Ψ1 → 0, f → ∞) of three tangential-spring rules with Mindlin's
stiffness, each integrated here (solve_ivp, rtol 1e-11), β = −Ψ2/Ψ1:
- perga's: the energy coordinate kept as δ changes, Ḟ_t = k_t s + F_t δ̇/(4δ);
- Mindlin & Deresiewicz (1953), incremental without slip: Ḟ_t = k_t s while the contact grows,
  Ḟ_t = k_t s + F_t ȧ/a = k_t s + F_t δ̇/(2δ) while it shrinks (the released annulus's share);
- a stretch kept as is, F_t = k_t(δ) ξ: Ḟ_t = k_t s + F_t δ̇/(2δ) throughout.

    python benchmarks/maw_barber_fawcett.py      # ~10 s
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.contact.soft.test_mindlin import DISC, KAPPA, NU, V_N, E, half_period, psi_2, row

from perga.analytic.contact import mindlin_ratio, tsuji_alpha
from perga.contact.soft import contact_duration

RESCALE = {"perga (energy)": 0.25, "Mindlin-Deresiewicz": None, "stretch": 0.5}
"""Each rule's c in Ḟ_t = k_t s + c F_t δ̇/δ (None: 0 while δ grows, ½ while it shrinks)."""


def full_stick_beta(ratio: float, e: float, rule: str) -> float:
    """β = −s_end/s_0 of a disc (I = m r²/2) sticking throughout its Hertz-Tsuji impact on a wall
    under ``rule``, in units m = k_n = v_n = s_0 = 1 (β is dimensionless and independent of
    them)."""
    damping = tsuji_alpha(e, "force")

    def rhs(_t, y):
        d, rate, slip, force = y
        d = max(d, 1e-300)
        fn = d**1.5 + damping * d**0.25 * rate
        share = RESCALE[rule]
        if share is None:
            share = 0.0 if rate > 0.0 else 0.5
        return [rate, -fn, -3.0 * force, ratio * math.sqrt(d) * slip + share * force * rate / d]

    def end(_t, y):  # F_n back to 0 (an undamped contact: δ back to 1e-9)
        d = y[0] - 1e-9
        return d**1.5 + damping * d**0.25 * y[1] if d > 0.0 else d

    end.terminal, end.direction = True, -1.0
    sol = solve_ivp(
        rhs, (0.0, 100.0), [1e-12, 1.0, 1.0, 0.0], method="DOP853", rtol=1e-11, atol=1e-14,
        events=end, max_step=0.01,
    )  # fmt: skip
    assert sol.status == 1, sol.message
    return -float(sol.y_events[0][0][2])


def main() -> None:
    mindlin = mindlin_ratio((E, math.inf), (NU, 0.3))
    print(
        f"κ = {KAPPA:.4f}, χ = 3(1 − ν)/(2 − ν) = {1.5 * KAPPA:.4f}, "
        f"Mindlin's k_t/k_n = {mindlin:.4f}"
    )
    for ratio in (2.0 / 7.0, mindlin):
        for e in (1.0, 0.7):
            resolved = row(ratio, e)
            t_c = contact_duration(resolved, DISC.m, 1.0, V_N)
            step = min(t_c, half_period(resolved)) / 50.0
            print(
                f"\nk_t/k_n = {ratio:.4f}, e = {e}: t_c = {t_c * 1e6:.1f} µs, tangential "
                f"half-period {half_period(resolved) * 1e6:.1f} µs, step {step * 1e6:.2f} µs"
            )
            print("   Ψ1   Ψ2 reference   Ψ2 kernel   gross-slip line   β = −Ψ2/Ψ1")
            for psi_1 in (0.1, 0.23, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 6.0):
                ref, kernel = psi_2(resolved, psi_1), psi_2(resolved, psi_1, step)
                line = psi_1 - 3.0 * KAPPA * (1.0 + e)
                print(
                    f"{psi_1:5.2f} {ref:+13.4f} {kernel:+11.4f} {line:+17.4f} {-ref / psi_1:+12.3f}"
                )
    print("\nfull stick (Ψ1 → 0), β:")
    for e in (1.0, 0.7):
        for ratio in (2.0 / 7.0, mindlin):
            betas = ", ".join(f"{rule} {full_stick_beta(ratio, e, rule):+.3f}" for rule in RESCALE)
            print(f"  e = {e}, k_t/k_n = {ratio:.4f}: {betas}")


if __name__ == "__main__":
    main()
