"""The units a separator's designer reads: rotor speed in rpm, hammer mass in g, fractions in
%, throughput in kg/h, energy in kJ/kg. Tables and files stay SI; plots and reports show a
quantity with :func:`axis_label` and :func:`metric_label`, its values times the factor."""

from __future__ import annotations

import math

from perga.stats.metrics import METRICS

AXES: dict[str, tuple[str, float]] = {
    "rotor.rpm": ("rotor speed [rpm]", 1.0),
    "rotor.omega": ("rotor speed [rpm]", 60.0 / (2.0 * math.pi)),
    "hammers.mass": ("hammer mass [g]", 1e3),
    "hammers.hinge_radius": ("hinge radius [mm]", 1e3),
    "rotor.radius": ("rotor radius [mm]", 1e3),
}
"""Case key -> (label with unit, factor from SI)."""

METRIC_UNITS: dict[str, tuple[str, float]] = {
    "released_fraction": ("released [%]", 100.0),
    "damaged_fraction": ("damaged [%]", 100.0),
    "throughput": ("throughput [kg/h]", 3600.0),
    "energy_per_kg": ("energy [kJ/kg]", 1e-3),
}
"""Metric -> (label with unit, factor from SI)."""


SI_UNITS: dict[str, str] = {
    "restitution": "-", "friction": "-", "rolling_friction": "-", "angle": "rad",
    "duration": "s", "dt": "s", "density": "kg/m³", "detachment_energy": "J",
    "detachment_force": "N", "speed": "m/s", "spin": "rad/s", "radius": "m", "mass": "kg",
    "youngs_modulus": "Pa", "poisson_ratio": "-",
}  # fmt: skip
"""A case key's last part -> its SI unit, for the keys not in :data:`AXES`."""


def axis_label(key: str) -> tuple[str, float]:
    """A case key's label and factor from SI; a key not listed keeps its name and its SI unit
    (by its last part, :data:`SI_UNITS`; "SI" where that is not known)."""
    if key in AXES:
        return AXES[key]
    return f"{key} [{SI_UNITS.get(key.rsplit('.', 1)[-1], 'SI')}]", 1.0


def si_label(metric: str) -> str:
    """A metric's name with its SI unit (:data:`perga.stats.metrics.METRICS`; "SI" for a name
    that is no metric): ``throughput [kg/s]``."""
    known = METRICS.get(metric.split(":", 1)[0])
    return f"{metric} [{known.unit if known else 'SI'}]"


def metric_label(metric: str) -> tuple[str, float]:
    """A metric's label and factor from SI; a metric not listed keeps its name and its SI unit
    (:func:`si_label`)."""
    return METRIC_UNITS.get(metric, (si_label(metric), 1.0))
