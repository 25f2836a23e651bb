"""Soft granules: spring-dashpot discs tuned to a restitution e, integrated by a numba kernel.

* ``laws``: the contact laws (linear, Hertz-Tsuji; Cundall-Strack tangential spring with
  Coulomb cap; rolling resistance) as pure numba functions, and the parameter table;
* ``neighbours``: cell list + Verlet half list with skin, history carried over rebuilds;
* ``kernel``: pair, wall and polygon forces, symplectic Euler, ``advance`` (k steps inside
  numba), the energy each contact law dissipated;
* ``polygon_set``: convex rigid polygons (hammers, a drawn wall), the granule-polygon contact
  table and the per-contact history;
* ``polygon_forces``: discs against those polygons, moved rigidly within a call, with mean
  loads and per-contact impact history;
* ``granules``: ``SoftGranules``, the Python holder with ``step(n)``, ``relax()`` and
  diagnostics (energies, ``contact_counts``).
"""

from perga.contact.soft.granules import DEFAULT_DT_FRACTION, SoftGranules, chamber, plane
from perga.contact.soft.laws import (
    N_PARAMS,
    contact_duration,
    contact_law,
    contact_parameters,
    pair_table,
    rolling_torque,
    uniform_table,
)

__all__ = [
    "DEFAULT_DT_FRACTION",
    "N_PARAMS",
    "SoftGranules",
    "chamber",
    "contact_duration",
    "contact_law",
    "contact_parameters",
    "pair_table",
    "plane",
    "rolling_torque",
    "uniform_table",
]
