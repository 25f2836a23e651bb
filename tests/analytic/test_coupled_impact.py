"""The impact law with a full effective-mass matrix (perga.analytic.coupled_impact) against the
diagonal oblique law and against an independent solver of the same complementarity problem."""

import math

import numpy as np
import pytest

from perga.analytic.coupled_impact import (
    coupled_impact,
    free_compliance,
    granule_compliance,
    pivoted_compliance,
)
from perga.analytic.impact import oblique_impact

M, R = 1.6e-4, 0.0025  # a bee-bread granule: kg, m
I_DISC = 0.5 * M * R**2


@pytest.mark.parametrize("rolls", [True, False])
@pytest.mark.parametrize(("u_t", "e", "f"), [(0.3, 0.7, 0.35), (3.0, 0.7, 0.35), (-2.0, 0.1, 1.0),
                                             (5.0, 0.95, 0.0), (0.0, 0.6, 0.5)])  # fmt: skip
def test_an_immovable_face_is_the_diagonal_oblique_law(u_t: float, e: float, f: float,
                                                       rolls: bool) -> None:  # fmt: skip
    """K = the granule's own: the closed form of perga.analytic.impact.oblique_impact (whose t
    is this module's −t), sticking and sliding, to rounding (1e-12 relative)."""
    inertia = I_DISC if rolls else math.inf
    law = coupled_impact(-2.0, u_t, e, f, granule_compliance(M, R, inertia))
    ref = oblique_impact(M, R, -2.0, -u_t, e, f, shape="disc" if rolls else "point")
    assert law.normal_impulse == pytest.approx(ref.normal_impulse, rel=1e-12)
    assert law.tangential_impulse == pytest.approx(-ref.tangential_impulse, rel=1e-12, abs=1e-18)
    assert law.tangential_velocity == pytest.approx(-ref.slip_after, rel=1e-12, abs=1e-12)
    assert law.normal_velocity == pytest.approx(ref.normal_velocity, rel=1e-12)
    assert law.sticks == (ref.sticks or u_t == 0.0)


def _projected_gauss_seidel(u: np.ndarray, e: float, f: float, K: np.ndarray) -> np.ndarray:
    """The same problem solved as an impulse solver does, row by row with accumulated impulses
    clamped to J_n >= 0 and |J_t| <= f·J_n, iterated to convergence: an independent method."""
    J = np.zeros(2)
    for _ in range(20_000):
        before = J.copy()
        J[0] = max(J[0] - (u[0] + K[0] @ J + e * u[0]) / K[0, 0], 0.0)
        J[1] = np.clip(J[1] - (u[1] + K[1] @ J) / K[1, 1], -f * J[0], f * J[0])
        if np.all(np.abs(J - before) <= 1e-14 * J[0]):
            return J
    raise AssertionError("the reference solver did not converge")


def test_a_hinged_or_free_hammer_couples_normal_and_slip() -> None:
    """200 random impacts on hinged (arms up to 0.14 m, 20-200 g plates) and free hammers:
    impulses equal the independent solver's to 1e-8 relative (its convergence), u_n' = −e·u_n,
    and either the slip stops within the cap or it slides at the cap without reversing."""
    rng = np.random.default_rng(5)
    coupled = 0
    for _ in range(200):
        n = np.array([math.cos(a := rng.uniform(0, 2 * math.pi)), math.sin(a)])
        arm = rng.uniform(-0.14, 0.14, 2)
        mass = rng.uniform(0.02, 0.2)
        moment = mass * 0.06**2 / 3
        hammer = (
            pivoted_compliance(moment, arm, n)
            if rng.random() < 0.7
            else free_compliance(mass, moment / 4, arm, n)
        )
        K = granule_compliance(M, R, I_DISC) + hammer
        coupled += abs(K[0, 1]) > 1e-3 * K[0, 0]
        u = np.array([-rng.uniform(0.1, 40.0), rng.uniform(-20.0, 20.0)])
        e, f = rng.uniform(0.05, 1.0), rng.uniform(0.0, 1.0)
        law = coupled_impact(u[0], u[1], e, f, K)
        J = _projected_gauss_seidel(u, e, f, K)
        assert law.normal_impulse == pytest.approx(J[0], rel=1e-8)
        assert law.tangential_impulse == pytest.approx(J[1], rel=1e-8, abs=1e-8 * J[0])
        after = u + K @ [law.normal_impulse, law.tangential_impulse]
        assert after[0] == pytest.approx(-e * u[0], rel=1e-12)
        assert after[1] == pytest.approx(law.tangential_velocity, abs=1e-9 * abs(u[0]))
        cap = f * law.normal_impulse
        if law.sticks:
            assert abs(law.tangential_impulse) <= cap * (1 + 1e-12)
        else:
            assert abs(law.tangential_impulse) == pytest.approx(cap, rel=1e-12)
            assert law.tangential_velocity * law.tangential_impulse <= 0.0
    assert coupled > 150  # the off-diagonal terms matter in most draws


def test_a_pivoted_hammer_struck_on_its_arms_line_takes_no_normal_impulse_share() -> None:
    """Struck at the hinge's own line of action (arm along n), a pivoted hammer cannot move
    along n: K_hammer = 0 along n and the normal impulse is a wall's, (1 + e)·m·|u_n|."""
    n = np.array([0.0, 1.0])
    K = granule_compliance(M, R, I_DISC) + pivoted_compliance(1e-4, [0.0, 0.1], n)
    law = coupled_impact(-3.0, 0.0, 0.6, 0.0, K)
    assert law.normal_impulse == pytest.approx(1.6 * M * 3.0, rel=1e-12)


@pytest.mark.parametrize(
    ("args", "message"),
    [((0.0, 1.0, 0.5, 0.3), "u_n"), ((-1.0, 1.0, 1.0001, 0.3), "e"),
     ((-1.0, 1.0, -1e-9, 0.3), "e"), ((-1.0, 1.0, 0.5, -1e-9), "f")],
)  # fmt: skip
def test_refusals(args: tuple, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        coupled_impact(*args, granule_compliance(M, R, I_DISC))
    coupled_impact(-1e-9, 1.0, 1.0, 0.0, granule_compliance(M, R, I_DISC))  # the edges pass


def test_a_compliance_that_is_not_positive_definite_is_refused() -> None:
    with pytest.raises(ValueError, match="positive definite"):
        coupled_impact(-1.0, 0.0, 0.5, 0.3, np.diag([1.0, 0.0]))
    coupled_impact(-1.0, 0.0, 0.5, 0.3, np.diag([1.0, 1e-12]))
