"""Granule sizes: every granule's radius (from ``granules.size`` or the one ``granules.radius``)
and mass, SI units.

A distribution by mass is turned into one by number: a granule of radius r weighs ρπr²t (t the
granules' thickness), so the number density is the mass density over r². Continuous
distributions are sampled by inverting their number CDF on a grid of 4,097 radii between the
bounds (linear interpolation: a relative error in r below 1e-6 for the bundled ones).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from perga.case.schema import Case, SizeDistribution

FloatArray = NDArray[np.float64]
GRID = 4097


def radius_range(case: Case) -> tuple[float, float]:
    """The smallest and largest radius a granule of the case can have, m."""
    size = case.granules.size
    if size is None:
        return case.granules.radius, case.granules.radius
    if size.kind == "table":
        assert size.radii is not None and size.fractions is not None
        present = [r for r, f in zip(size.radii, size.fractions, strict=True) if f > 0]
        return min(present), max(present)
    assert size.low is not None and size.high is not None
    return size.low, size.high


def _number_weights(size: SizeDistribution, r: FloatArray) -> FloatArray:
    """The distribution's density at radii ``r`` by number (unnormalised)."""
    from scipy import stats  # here, not at import: it costs a quarter second of a run's start

    if size.kind == "uniform":
        density = np.ones_like(r)
    elif size.kind == "normal":
        density = stats.norm.pdf(r, size.mean, size.sd)
    elif size.kind == "lognormal":
        assert size.median is not None and size.sigma is not None
        density = stats.lognorm.pdf(r, size.sigma, scale=size.median)
    else:  # table: weights of its discrete radii
        density = np.asarray(size.fractions, dtype=float)
    return density / r**2 if size.basis == "mass" else density


def draw_radii(case: Case, count: int, rng: np.random.Generator) -> FloatArray:
    """``count`` radii of the case's granules, m (all ``granules.radius`` without a size)."""
    size = case.granules.size
    if size is None:
        return np.full(count, case.granules.radius)
    if size.kind == "table":
        radii = np.asarray(size.radii, dtype=float)
        weights = _number_weights(size, radii)
        return rng.choice(radii, size=count, p=weights / weights.sum())
    lo, hi = radius_range(case)
    grid = np.linspace(lo, hi, GRID)
    density = _number_weights(size, grid)
    cdf = np.concatenate(([0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(grid))))
    if not cdf[-1] > 0:
        raise ValueError("granules.size: the distribution has no weight between low and high")
    return np.interp(rng.uniform(0.0, cdf[-1], count), cdf, grid)


def masses(case: Case, radii: FloatArray) -> FloatArray:
    """Each granule's mass, kg: ``granules.mass``, or ρπr²·thickness."""
    g = case.granules
    if g.mass is not None and g.size is None:
        return np.full(len(radii), g.mass)
    return case.granule_density * math.pi * np.asarray(radii) ** 2 * case.granule_thickness


def initial_radii(case: Case) -> FloatArray:
    """The radii of the granules present at t = 0 (seeded by ``solver.seed``), m."""
    rng = np.random.default_rng(np.random.SeedSequence(case.solver.seed, spawn_key=(1,)))
    return draw_radii(case, case.granules.count, rng)


def quantile_table(case: Case) -> tuple[FloatArray, FloatArray, bool]:
    """The radius distribution as (radii, cumulative number probabilities, discrete): the
    listed radii of a table or the one radius (discrete), or a grid with its number CDF."""
    size = case.granules.size
    if size is None:
        return np.array([case.granules.radius]), np.array([1.0]), True
    if size.kind == "table":
        radii = np.asarray(size.radii, dtype=float)
        order = np.argsort(radii)
        weights = _number_weights(size, radii)[order]
        return radii[order], np.cumsum(weights) / weights.sum(), True
    lo, hi = radius_range(case)
    grid = np.linspace(lo, hi, GRID)
    density = _number_weights(size, grid)
    cdf = np.concatenate(([0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(grid))))
    return grid, cdf / cdf[-1], False


def mean_mass(case: Case) -> float:
    """The mean mass of a granule drawn from the case's sizes, kg."""
    radii, levels, discrete = quantile_table(case)
    if discrete:
        p = np.diff(np.concatenate(([0.0], levels)))
        return float(np.sum(p * masses(case, radii)))
    m = masses(case, radii)
    return float(np.sum(0.5 * (m[1:] + m[:-1]) * np.diff(levels)))
