"""A spinning disc's kinetic energy in the impact statistics (perga.stats.energy): translation
½mv² and spin ½Iω² with I = ½mr² (a disc about its axis), against the closed form. Synthetic
tables: exact, so the tolerance is round-off (1e-12)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from perga.case import load_case
from perga.stats import Run
from perga.stats.energy import granule_energy, impact_stats, successive_energies

CASES = Path(__file__).resolve().parents[2] / "cases"
M, R = 0.2e-3, 3.0e-3  # kg, m: the granule
V, SPIN = (3.0, -4.0), 2000.0  # m/s, rad/s: before the impact
GAIN = 2.5e-4  # J: the impact's recorded granule energy gain


def _closed_form() -> float:
    """½m|v|² + ½(½mr²)ω², J."""
    return 0.5 * M * math.hypot(*V) ** 2 + 0.5 * (0.5 * M * R**2) * SPIN**2


def _run(tmp_path: Path, own_sizes: bool) -> Run:
    """Granule 0 moving at V and spinning at SPIN until an impact at t = 1 s (frames at 0.5 and
    1.5 s); its mass and radius the case's, or (``own_sizes``) its own columns of
    granules.csv, the case's being other values."""
    case = load_case(CASES / "two-body-impact.toml")
    assert case.granules.rolls
    g = case.granules
    case_sizes = {"mass": 2 * M, "radius": 2 * R} if own_sizes else {"mass": M, "radius": R}
    case = case.model_copy(update={"granules": g.model_copy(update=case_sizes)})
    granules = {
        "time": np.array([0.5, 1.5]),
        "id": np.zeros(2),
        "speed": np.full(2, math.hypot(*V)),
        "angular_velocity": np.full(2, SPIN),
    }
    if own_sizes:
        granules |= {"mass": np.full(2, M), "radius": np.full(2, R)}
    impacts = {
        "time": np.array([1.0]),
        "granule": np.zeros(1),
        "hammer": np.zeros(1),
        "normal_velocity_before": np.array([-5.0]),
        "normal_velocity_after": np.array([3.0]),
        "tangential_velocity_before": np.array([1.0]),
        "tangential_velocity_after": np.array([0.5]),
        "granule_spin_before": np.array([SPIN]),
        "granule_spin_after": np.array([SPIN / 2]),
        "normal_impulse": np.array([1e-3]),
        "granule_energy_gain": np.array([GAIN]),
        "dissipated": np.array([1e-4]),
        "hammer_energy_before": np.array([1.0]),
    }
    return Run(tmp_path, case, {}, granules, {}, impacts, {})


@pytest.mark.parametrize("own_sizes", [False, True], ids=["case-sizes", "own-sizes"])
def test_the_energy_of_a_spinning_disc_includes_its_spin(tmp_path: Path, own_sizes: bool) -> None:
    """Before the impact, after it, the impact's lab energy and loss, and the successive
    energies all take ½mv² + ¼mr²ω² (the spin's share here 0.42)."""
    run = _run(tmp_path, own_sizes)
    energy = _closed_form()
    assert 0.5 * 0.5 * M * R**2 * SPIN**2 / energy == pytest.approx(0.42, abs=0.01)
    assert granule_energy(run, 0, 1.0) == pytest.approx(energy, rel=1e-12)
    assert granule_energy(run, 0, 1.0, before=False) == pytest.approx(energy, rel=1e-12)
    stats = impact_stats(run, 0)
    assert stats.lab_energy_before == pytest.approx(energy, rel=1e-12)
    assert stats.lab_loss == pytest.approx(-GAIN / energy, rel=1e-12)
    lab = successive_energies(run).lab
    assert lab == pytest.approx([energy + GAIN], rel=1e-12)
