"""Every free flight of a run's granules between two of their hammer contacts against the
flight over the floor (:mod:`perga.analytic.floor_flight`: Coulomb friction against the
velocity relative to the floor, quadratic drag), started from the state the first contact ended
with (contacts.csv) and compared where the next began: the position there (contacts.csv) and
the velocity just before its impulses (impacts.csv).

A **flight** is the time between two contacts of a granule with the hammers that lasts at
least a contact time (:func:`perga.stats.slide_law.contact_time`). It is **free** when the
granule touched nothing else meanwhile: it began no contact with another granule or the wall
between them (contacts.csv's ``touches`` the same at both) and had none during the first
contact (its ``other_contacts`` 0), and it was not held in a cell. Soft contacts do not count
a granule's touches: their flights cannot be told free.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np

from perga.analytic.floor_flight import FloorFlight
from perga.model.compile import compile_case
from perga.stats.episodes import in_words, median_and_largest
from perga.stats.slide_law import contact_time
from perga.stats.tables import Run

FREE = "free"


@dataclass(frozen=True)
class FlightCheck:
    """One flight, simulated against the model at its end (SI; errors dimensionless)."""

    granule: int
    start: float
    duration: float
    regime: str
    """``FREE``, or why the model cannot describe this flight."""
    velocity_error: float
    """|v_sim − v_model| / |v_model| just before the next impact, fixed frame."""
    position_error: float
    """|r_sim − r_model| over the model's path length, where the next contact began."""
    speed: tuple[float, float]
    """|v| just before the next impact, m/s, simulated and model."""


def _unavailable(run: Run) -> str | None:
    """Why no flight of ``run`` can be predicted, or None."""
    c = run.contacts
    if not c or "touches" not in c:
        return "no contacts.csv with the granules' touches (not recorded, or an older run)"
    if c["touches"].size and np.all(c["touches"] < 0):
        return "soft contacts do not count a granule's touches of other granules and the wall"
    if run.case.effects.gravity_in_plane is not None:
        return "gravity in the plane of a vertical rotor (the model has the floor's only)"
    return None


def _model(run: Run) -> tuple[FloorFlight, dict[int, float]]:
    """The floor flight of ``run``'s case and each granule's drag coefficient k (1/m)."""
    system = compile_case(run.case)
    floor, drag = system.effects.floor_friction, system.effects.air_drag
    omega = run.omega if floor is not None and floor.floor == "corotating" else 0.0
    flight = FloorFlight(omega, 0.0 if floor is None else floor.friction, run.case.gravity)
    ids = run.granules["id"].astype(int)
    radius = dict(zip(ids, run.granules["radius"], strict=True))
    mass = dict(zip(ids, run.granules["mass"], strict=True))
    if drag is None:
        return flight, {}
    area = {g: 2 * radius[g] * drag.thickness for g in radius}
    half_rho_cd = 0.5 * drag.air_density * drag.drag_coefficient
    return flight, {g: half_rho_cd * area[g] / mass[g] for g in radius}


def _regime(before: dict[str, float], after: dict[str, float]) -> str:
    if before["held"]:
        return "the granule was held in the comb"
    if before["other_contacts"] > 0 or after["touches"] != before["touches"]:
        return "it touched another granule or the wall"
    return FREE


def check_flights(run: Run) -> list[FlightCheck]:
    """Every flight of ``run`` against the model; ValueError (its reason) where none can be
    predicted."""
    if reason := _unavailable(run):
        raise ValueError(f"{run.name}: {reason}")
    flight, drag = _model(run)
    c, imp = run.contacts, run.impacts
    before_impact = {
        (int(g), int(h), float(t)): i
        for i, (g, h, t) in enumerate(zip(imp["granule"], imp["hammer"], imp["time"], strict=True))
    }
    shortest = contact_time(run) * (1 - 1e-9)  # times are sums of steps: rounding
    checks = []
    order = np.lexsort((c["start"], c["granule"]))
    for a, b in pairwise(order):
        if c["granule"][a] != c["granule"][b] or c["start"][b] - c["end"][a] < shortest:
            continue
        first = {k: float(v[a]) for k, v in c.items()}
        second = {k: float(v[b]) for k, v in c.items()}
        row = before_impact.get((int(second["granule"]), int(second["hammer"]), second["start"]))
        if row is None:
            continue
        g, T = int(first["granule"]), second["start"] - first["end"]
        model = FloorFlight(flight.omega, flight.friction, flight.gravity, drag.get(g, 0.0))
        result = model.integrate(
            (first["x_end"], first["y_end"]), (first["vx_end"], first["vy_end"]), T
        )
        v_sim = np.array([imp["vx_before"][row], imp["vy_before"][row]])
        r_sim = np.array([second["x_start"], second["y_start"]])
        v_law, r_law = result.v[-1], result.r[-1]
        path = float(np.sum(np.hypot(*np.diff(result.r, axis=0).T))) or 1.0
        caught = result.event == "caught"
        checks.append(
            FlightCheck(
                granule=g,
                start=first["end"],
                duration=T,
                regime="the floor catches the granule" if caught else _regime(first, second),
                velocity_error=math.nan
                if caught
                else float(np.hypot(*(v_sim - v_law)) / np.hypot(*v_law)),
                position_error=math.nan if caught else float(np.hypot(*(r_sim - r_law))) / path,
                speed=(float(np.hypot(*v_sim)), float(np.hypot(*v_law))),
            )
        )
    return checks


@dataclass(frozen=True)
class FlightSummary:
    """A run's checked flights taken together (:func:`summarise_flights`)."""

    checks: list[FlightCheck]
    free: list[FlightCheck]
    regimes: Counter[str] = field(default_factory=Counter)

    @property
    def others(self) -> str:
        """The regimes but ``FREE`` in words, most frequent first."""
        return in_words(self.regimes)

    def worst(self, count: int) -> list[FlightCheck]:
        """The ``count`` free flights with the largest velocity errors, largest first."""
        return sorted(self.free, key=lambda c: -c.velocity_error)[:count]

    def statistics(self) -> dict[str, dict[str, float]]:
        """Median and largest error of the free flights' velocity and position at their end."""
        return median_and_largest(
            {
                "velocity before the next impact": [c.velocity_error for c in self.free],
                "position at the next contact (over the path)": [
                    c.position_error for c in self.free
                ],
            }
        )


def summarise_flights(checks: list[FlightCheck]) -> FlightSummary:
    """``checks`` taken together: the free ones and the other regimes."""
    free = [c for c in checks if c.regime == FREE]
    return FlightSummary(checks, free, Counter(c.regime for c in checks if c.regime != FREE))
