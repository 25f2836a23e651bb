"""The vocabulary of ``perga compare``: a :class:`Row` (a statistic of a run against the
analytical value it is compared with), an :class:`Unavailable` statistic and the
:class:`Analysis` of one run or sweep that holds them."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

from perga.stats.tables import Run

AGREEMENT = 0.01
"""Relative tolerance where simulation and analytical model describe the same physics: the
issue's 1 %. The rigid engine reproduces the closed forms to 1e-4-5e-4 at the bundled steps
(docs/dev/validation.md), so 1 % catches any modelling error with a margin of 20 or more."""


@dataclass(frozen=True)
class Row:
    """One statistic: simulated against analytical, with the error and the reason."""

    run: str
    figure: str
    quantity: str
    simulated: float
    analytic: float
    model: str
    tolerance: float | None
    """Relative tolerance where the physics is the same; None where it differs."""
    reason: str
    unit: str = "-"

    @property
    def error(self) -> float:
        """(simulated − analytic)/|analytic|, -."""
        if self.analytic == 0:
            return math.inf if self.simulated else 0.0
        return (self.simulated - self.analytic) / abs(self.analytic)

    @property
    def agrees(self) -> bool | None:
        """|error| ≤ tolerance, or None for a row that is not expected to agree."""
        return None if self.tolerance is None else abs(self.error) <= self.tolerance

    def as_dict(self) -> dict[str, object]:
        """Plain data for JSON."""
        return asdict(self) | {"error": self.error, "agrees": self.agrees}


@dataclass(frozen=True)
class Unavailable:
    """A statistic that could not be computed for a run, and why."""

    run: str
    statistic: str
    reason: str


@dataclass
class Analysis:
    """The rows of one run (or sweep), the statistics it could not give (:class:`Unavailable`)
    and the series its figures draw (SI units)."""

    name: str
    kind: str
    rows: list[Row] = field(default_factory=list)
    series: dict[str, object] = field(default_factory=dict)
    unavailable: list[Unavailable] = field(default_factory=list)

    def cannot(self, run: Run, statistic: str, reason: str) -> None:
        """Record that ``statistic`` of ``run`` could not be computed, and why."""
        self.unavailable.append(Unavailable(run.name, statistic, reason))


def missing_impacts(run: Run, needed: int = 1) -> str | None:
    """Why ``run`` has fewer than ``needed`` granule-hammer impacts, or None if it has them."""
    if not run.impacts:
        return "the run did not record impacts (output.record lacks 'impacts')"
    n = run.impacts["time"].size
    if n >= needed:
        return None
    simulated = run.summary.get("simulated_time") or 0.0
    return (
        f"{n} granule-hammer impacts completed in the run's {simulated:.3g} s; this needs {needed}"
    )
