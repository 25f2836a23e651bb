"""The contact laws (perga.contact.laws) against the closed forms of perga.analytic.contact.

Where a law hands on a closed form the test asks for the same float (exact equality: the laws
must not change a step, a stiffness or a kernel row by one ulp); round trips through a
closed form and its inverse are held to 1e-12 relative (a few ulps of each float operation).
"""

import math
import subprocess
import sys

import numpy as np
import pytest

from perga.analytic.contact import (
    FORCE_END_MIN_RESTITUTION,
    HertzTsuji,
    LinearSpringDashpot,
    damping_ratio,
    hertz_stiffness,
    mindlin_ratio,
    tsuji_alpha,
)
from perga.contact.laws import LAWS, contact_law
from perga.contact.laws.base import ContactLaw
from perga.contact.laws.hertz import Hertz
from perga.contact.laws.linear import Linear
from perga.contact.laws.row import (
    HERTZ,
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

ENDS = ("force", "overlap")
RESTITUTIONS = (0.2, 0.5, 0.7, 0.95, 1.0)
M, R, V = 1.6e-4, 2.5e-3, 12.0  # kg, m, m/s: a bee-bread granule at a hammer's speed


def test_the_registry_names_each_law() -> None:
    assert type(contact_law("linear")) is Linear
    assert type(contact_law("hertz")) is Hertz
    assert all(isinstance(contact_law(name), ContactLaw) for name in LAWS)


def test_an_unknown_law_is_refused_with_the_known_ones_named() -> None:
    with pytest.raises(ValueError, match="unknown contact law 'cohesive': one of linear, hertz"):
        contact_law("cohesive")


@pytest.mark.parametrize("end", ENDS)
@pytest.mark.parametrize("e", RESTITUTIONS)
def test_damping_is_the_closed_forms(e: float, end: str) -> None:
    linear, hertz = Linear(), Hertz()
    assert linear.damping_ratio(e, end) == hertz.damping_ratio(e, end) == damping_ratio(e, end)
    assert linear.damping(e, end) == damping_ratio(e, end)
    assert linear.kernel_damping(e, end) == 2.0 * damping_ratio(e, end)
    assert hertz.damping(e, end) == hertz.kernel_damping(e, end) == tsuji_alpha(e, end)


@pytest.mark.parametrize("law", [Linear(), Hertz()], ids=["linear", "hertz"])
@pytest.mark.parametrize("end", ENDS)
def test_the_reachable_range_is_where_damping_exists(law: ContactLaw, end: str) -> None:
    """Just inside (low, high] e has a damping; at low, just below it and just above 1, none."""
    low, high = law.reachable(end)
    assert (low, high) == ((FORCE_END_MIN_RESTITUTION if end == "force" else 0.0), 1.0)
    for e in (math.nextafter(low, 1.0) * (1 + 1e-12), high):
        assert 0.0 <= law.damping(e, end) < math.inf
    for e in (low, math.nextafter(low, 0.0), math.nextafter(high, 2.0)):
        with pytest.raises(ValueError):
            law.damping(e, end)


@pytest.mark.parametrize("end", ENDS)
@pytest.mark.parametrize("e", (0.3, 0.7, 1.0))
def test_linear_stiffness_and_duration(e: float, end: str) -> None:
    law, t_c = Linear(), 1e-4
    k = law.stiffness_for_duration(t_c, e, M, R, V, end)
    assert k == LinearSpringDashpot.from_duration(t_c, e, M, end).k
    assert (
        law.duration(k, e, M, R, V, end)
        == LinearSpringDashpot.from_stiffness(k, e, M, end).duration
    )
    assert law.duration(k, e, M, R, V, end) == pytest.approx(t_c, rel=1e-12)
    assert law.fixed_duration  # the mass fixes it: any radius, any speed
    assert law.duration(k, e, M, 10 * R, 3 * V, end) == law.duration(k, e, M, R, V, end)
    assert law.sticking_stiffness(k, M, R, V) == k


@pytest.mark.parametrize("end", ENDS)
@pytest.mark.parametrize("e", (0.3, 0.7, 1.0))
def test_hertz_stiffness_and_duration(e: float, end: str) -> None:
    """k_n from t_c gives back t_c at the granule's radius and the fastest speed; the duration
    is HertzTsuji's at contact stiffness k_n√r_eff."""
    law, t_c, k_n = Hertz(), 1e-4, 1e9
    duration = law.duration(k_n, e, M, R, V, end)
    contact = HertzTsuji.from_restitution(k_n * math.sqrt(R), e, M, end)
    assert duration == contact.impact(V).duration
    k = law.stiffness_for_duration(t_c, e, M, R, V, end)
    assert law.duration(k, e, M, R, V, end) == pytest.approx(t_c, rel=1e-12)
    assert not law.fixed_duration
    assert law.duration(k, e, M, R, 2 * V, end) < t_c  # shorter when faster: t_c at v is the least


@pytest.mark.parametrize("v", (0.5, 12.0, 80.0))
def test_hertz_sticking_stiffness_is_the_secant_at_the_peak_overlap(v: float) -> None:
    """k_n√(R*δ_max), δ_max the undamped closed form (5 m v²/(4 k_n√R*))^{2/5} (Johnson 1985)."""
    k_n = 1e9
    peak = HertzTsuji(k_n * math.sqrt(R), 0.0, M).impact(v).peak_overlap
    expected = k_n * math.sqrt(R * peak)
    assert Hertz().sticking_stiffness(k_n, M, R, v) == pytest.approx(expected, rel=1e-12)


def test_stiffness_from_the_materials() -> None:
    """Hertz: (4/3)E*, the Hertz stiffness of a unit radius; linear takes none."""
    E, nu = (5e6, 2.1e11), (0.3, 0.29)
    assert Hertz.from_materials and not Linear.from_materials
    assert Hertz().stiffness_from_materials(E, nu) == hertz_stiffness(E, nu, 1.0)
    with pytest.raises(ValueError, match="Linear takes no stiffness from the materials"):
        Linear().stiffness_from_materials(E, nu)


def test_tangential_ratio_limits() -> None:
    """Hertz's largest k_t/k_n is Mindlin's 6G*/E* as ν → −1 (on the secant k_n√(R*δ)); the
    linear law's is the same on the tangent stiffness, 1.5 times the secant (dF/dδ of
    k δ^{3/2}); both default to LAMMPS's 2/7, and only Hertz takes Mindlin's."""
    nus = np.linspace(-0.999999, 0.5, 101)
    ratios = [mindlin_ratio((1e7, math.inf), (nu, 0.3)) for nu in nus]
    assert max(ratios) <= Hertz.max_tangential_ratio
    assert ratios[0] == pytest.approx(Hertz.max_tangential_ratio, rel=1e-6)
    assert Linear.max_tangential_ratio == Hertz.max_tangential_ratio / 1.5
    assert Linear.default_tangential_ratio == Hertz.default_tangential_ratio == 2.0 / 7.0
    assert Hertz.mindlin and not Linear.mindlin


@pytest.mark.parametrize(("law", "form"), [(Linear(), LINEAR), (Hertz(), HERTZ)])
@pytest.mark.parametrize("end", ENDS)
def test_the_kernel_row(law: ContactLaw, form: int, end: str) -> None:
    row = law.row(0.6, 2e4, friction=0.4, rolling=0.01, kt_ratio=0.5, zeta_t=0.1, end=end)
    assert row.shape == (N_PARAMS,) and row.dtype == np.float64
    assert row[P_KN] == 2e4 and row[P_KT] == 1e4 and row[P_DAMPT] == 0.1
    assert row[P_MU] == 0.4 and row[P_MUR] == 0.01
    assert row[P_DAMP] == law.kernel_damping(0.6, end)
    assert row[P_HERTZ] == form
    assert row[P_CLAMP] == (1.0 if end == "force" else 0.0)


def test_the_laws_load_without_the_kernel() -> None:
    """The laws load neither numba nor the soft kernel, and the case and the system, which ask
    them, do not load the kernel."""
    code = (
        "import sys; from perga.contact.laws import LAWS, contact_law;"
        "[contact_law(n) for n in LAWS]; loaded = lambda: sorted("
        "m for m in ('perga.contact.soft', 'numba') if m in sys.modules); print(loaded());"
        "import perga.model.plan, perga.model.compile; print(loaded())"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.split("\n")[:2] == ["[]", "['numba']"]  # numba: perga.geometry's compiled parts


@pytest.mark.parametrize(("e", "end"), [(0.6, "force"), (0.3, "overlap")])
def test_the_normal_force_in_closed_form(e: float, end: str) -> None:
    """F(δ, δ̇) of each law from the closed forms' own coefficients (the same floats: exact),
    clamped at zero when the contact ends at zero force (a pulling rate shows it)."""
    k_n, m, r = 2e5, 1e-4, 2e-3
    linear = LinearSpringDashpot.from_stiffness(k_n, e, m, end)
    hertz = HertzTsuji.from_restitution(k_n * math.sqrt(r), e, m, end)
    for delta, rate in ((1e-5, 0.5), (2e-5, -0.3), (1e-6, -50.0)):
        expected = (
            linear.k * delta + linear.c * rate,
            hertz.k_n * delta**1.5 + hertz.eta * delta**0.25 * rate,
        )
        for law, value in zip((Linear(), Hertz()), expected, strict=True):
            force = law.normal_force(k_n, e, m, r, end)(delta, rate)
            assert force == (max(value, 0.0) if end == "force" else value)
