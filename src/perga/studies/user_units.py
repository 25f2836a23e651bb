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


def axis_label(key: str) -> tuple[str, float]:
    """A case key's label and factor from SI; a key not listed keeps its name, in SI."""
    return AXES.get(key, (f"{key} [SI]", 1.0))


def metric_label(metric: str) -> tuple[str, float]:
    """A metric's label and factor from SI; a metric not listed keeps its name and its SI unit
    (:data:`perga.stats.metrics.METRICS`; "SI" for a name that is no metric)."""
    if metric in METRIC_UNITS:
        return METRIC_UNITS[metric]
    known = METRICS.get(metric.split(":", 1)[0])
    return f"{metric} [{known.unit if known else 'SI'}]", 1.0
