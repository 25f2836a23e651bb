"""Statistics of recorded runs: pure functions of a run directory's tables (SI units).

:mod:`perga.stats.tables` loads a run (granules.csv, hammers.csv, impacts.csv, energy.csv,
summary.json, case.toml); :mod:`perga.stats.trajectory` gives radial coordinates, positions in
a blade's rotating frame, amplitude fractions, fitted exponential rates and the free flight
over a Coulomb floor; :mod:`perga.stats.energy` gives per-impact restitution, energy losses in
the hammer and lab frames, every efficiency of :func:`perga.analytic.impact.impact_efficiencies`,
the hinged-hammer prediction, cumulative energies over successive impacts and impact-speed
histograms; :mod:`perga.stats.sweeps` collects sweeps (efficiency against hammer mass, blade
exit speed maps).
"""

from perga.stats.tables import Run, load_run

__all__ = ["Run", "load_run"]
