"""perga paper-check: the table's verdicts and numbers, the fits behind the case files, the CLI."""

import json
import math
from pathlib import Path

import pytest

from perga.analytic.paper import PaperRadialMotion, paper_roots
from perga.case import load_case
from perga.cli import main
from perga.studies.paper_check import (
    Params,
    check_paper,
    fit_decay_omega,
    fit_granule_mass,
    two_body_efficiency,
)

FITTED = load_case("cases/paper-fitted.toml")
REALISTIC = load_case("cases/paper-realistic.toml")
ROWS = {row.key: row for row in check_paper(FITTED, REALISTIC)}
FIT, REAL = Params.from_case(FITTED), Params.from_case(REALISTIC)

# (fitted verdict, realistic verdict) for every row: a change in any physics or any parameter
# that flips a verdict must be a deliberate edit here and in docs/explanation/paper-notes.md.
EXPECTED_VERDICTS = {
    "decay-0.02s": ("yes", "yes"),
    "decay-0.05s": ("yes", "yes"),
    "radius-0.05s": ("yes", "no"),
    "efficiency-5g": ("partly", "no"),
    "efficiency-100g": ("partly", "no"),
    "efficiency-200g": ("partly", "no"),
    "efficiency-optimum": ("partly", "partly"),
    "loss-per-impact": ("yes", "yes"),
    "successive-radii": ("yes", "yes"),
    "energy-by-third": ("yes", "no"),
    "vmax-omega": ("yes", "yes"),
    "vmax-friction": ("partly", "partly"),
    "damped-oscillation": ("no", "no"),
    "eq1-6-7": ("no", "no"),
    "eq8": ("partly", "partly"),
    "eq14-24": ("yes", "yes"),
    "eq38-40": ("yes", "no"),
    "eq53-54": ("no", "no"),
    "eq57": ("partly", "partly"),
    "eq59": ("no", "no"),
}


def test_every_row_has_the_expected_verdicts():
    got = {key: (row.fitted.verdict, row.realistic.verdict) for key, row in ROWS.items()}
    assert got == EXPECTED_VERDICTS


def test_fitted_case_holds_the_fits():
    # the case file keeps 9-10 significant digits of each fit: compare at 1e-8 relative
    study = FITTED.paper
    omega = fit_decay_omega(FIT.f, study, FIT.g)
    assert FIT.omega == pytest.approx(omega, rel=1e-8)
    mass, _ = fit_granule_mass(study, FIT.e, scale=100)
    assert FIT.m == pytest.approx(mass, rel=1e-8)
    # at the fitted ω the stricter claim (60 % by 0.02 s) holds with equality
    left = PaperRadialMotion.decaying_branch(FIT.omega, FIT.f, 0.08).displacement(0.02) / 0.08
    assert left == pytest.approx(0.4, rel=1e-8)


def test_decay_numbers_follow_the_closed_form():
    # on the decaying branch x + a = (x0 + a) e^{λ2 t}, a = fg/ω²
    for p, key in ((FIT, "fitted"), (REAL, "realistic")):
        lam2 = paper_roots(p.omega, p.f)[1]
        a = p.f * p.g / p.omega**2
        for t, row in ((0.02, "decay-0.02s"), (0.05, "decay-0.05s")):
            lost = 1 - ((0.08 + a) * math.exp(lam2 * t) - a) / 0.08
            assert getattr(ROWS[row], key).numbers["fraction_lost"] == pytest.approx(
                lost, rel=1e-12
            )


def test_efficiency_rows_are_the_two_body_law():
    for mass_g, key in ((5, "efficiency-5g"), (100, "efficiency-100g"), (200, "efficiency-200g")):
        M = mass_g / 1000
        for p, which in ((FIT, "fitted"), (REAL, "realistic")):
            expected = (1 + p.e) ** 2 * p.m * M / (M + p.m) ** 2
            got = getattr(ROWS[key], which).numbers["efficiency"]
            assert got == pytest.approx(expected, rel=1e-12)
    # read as per cent, no granule mass fits: the paper's ratio η(5 g)/η(100 g) is 7.5, the law's
    # is (5/100)·((100 + m)/(5 + m))², which falls to 7.5 only at m ≈ 3.4 g, where η(5 g) ≈ 0.7
    m_best, rms = fit_granule_mass(FITTED.paper, 0.7)
    assert rms > math.log(1.5)
    assert two_body_efficiency(m_best, 0.005, 0.7) > 0.01


def test_paper_loss_per_impact_is_one_minus_e_squared():
    assert ROWS["loss-per-impact"].fitted.numbers["normal"] == pytest.approx(1 - 0.7**2, rel=1e-12)


def test_the_45_degree_loss_names_its_granule():
    """At 45° (|v| = 1) a point mass sliding throughout keeps e·v_n normally and
    v_t − f(1 + e)|v_n| tangentially: it loses 1 − (e² + (1 − f(1 + e))²)/2 of its energy. A
    disc's friction also spins it up, so its slip stops and it loses less; the row gives both."""
    row = ROWS["loss-per-impact"].fitted
    e, f = FIT.e, FIT.f
    assert f * (1 + e) < 1  # the point mass slides throughout
    assert row.numbers["oblique_45"] == pytest.approx(1 - (e**2 + (1 - f * (1 + e)) ** 2) / 2)
    assert row.numbers["oblique_45_disc"] < row.numbers["oblique_45"]
    assert "(point mass)" in row.value and "(disc, sticking)" in row.value


def test_a_claim_the_fit_was_made_for_says_so():
    """The fitted ω puts decay-0.02s on its bound (margin ~1e-13): the row shows the margin and
    says the fit makes the claim hold; a claim with room does not say it."""
    fitted = ROWS["decay-0.02s"].fitted
    assert abs(fitted.numbers["margin"]) < 1e-9
    assert "holds by construction" in fitted.value
    for row in (ROWS["decay-0.02s"].realistic, ROWS["decay-0.05s"].fitted):
        assert row.numbers["margin"] > 0.1 and "by construction" not in row.value


def test_successive_fit_and_energy():
    numbers = ROWS["successive-radii"].fitted.numbers
    assert numbers["max_relative_error"] < 0.1
    # β is much smaller than the paper's own decay rate |λ2|
    assert numbers["beta"] < 0.5 * -paper_roots(FIT.omega, FIT.f)[1]
    assert ROWS["energy-by-third"].fitted.numbers["restitution"] == pytest.approx(1 - 0.7**6)


def test_json_cli_lists_every_row(capsys):
    assert main(["paper-check", "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [c["key"] for c in data["claims"]] == list(EXPECTED_VERDICTS)
    assert data["parameters"]["fitted"]["omega"] == pytest.approx(FIT.omega)


def test_markdown_and_plots(tmp_path, capsys):
    assert main(["paper-check", "--format", "markdown", "--plots", str(tmp_path)]) == 0
    table = capsys.readouterr().out.splitlines()
    assert table[0].startswith("| claim | paper |")
    assert len(table) == 2 + len(EXPECTED_VERDICTS)
    assert sorted(p.stem for p in tmp_path.glob("*.png")) == sorted(EXPECTED_VERDICTS)


def test_bad_case_exits_2_with_the_problem(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        Path("cases/paper-realistic.toml").read_text().replace("rpm = 600.0", "rmp = 600.0")
    )
    assert main(["paper-check", "--realistic", str(bad)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}: rotor.rmp: unknown key; did you mean 'rpm'?" in err
