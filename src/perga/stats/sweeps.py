"""Statistics over sweeps of runs: blade exit speed (v_max maps) and efficiency against hammer
mass (SI units)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perga.stats.energy import impact_stats
from perga.stats.tables import Run
from perga.stats.trajectory import blade_frame

FloatArray = NDArray[np.float64]


def blade_tip(run: Run) -> float:
    """Distance of a radial blade's outer end from the axis, m (plate hammers)."""
    h = run.case.hammers
    return h.hinge_radius + h.shape.length - h.shape.hinge_offset


def blade_exit(run: Run, granule: int = 0) -> tuple[float, float]:
    """(time in s, fixed-frame speed in m/s) when the granule's centre passes the blade's tip,
    interpolated linearly between the two frames around it; (nan, nan) if it never does.

    The blade is hammer 0 of a welded radial plate; on the blade the speed only grows while the
    granule slides out, so this is the largest speed it reaches on the blade (v_max)."""
    track = run.track(granule)
    t = track["time"]
    along, _, _ = blade_frame(
        track["x"], track["y"], track["vx"], track["vy"], run.rotor_angle(t), run.omega
    )
    past = np.nonzero(along >= blade_tip(run))[0]
    if not past.size or past[0] == 0:
        return math.nan, math.nan
    i = int(past[0])
    s = (blade_tip(run) - along[i - 1]) / (along[i] - along[i - 1])
    speed = track["speed"]
    return float(t[i - 1] + s * (t[i] - t[i - 1])), float(
        speed[i - 1] + s * (speed[i] - speed[i - 1])
    )


@dataclass(frozen=True)
class EfficiencyPoint:
    """The first impact of one run of a hammer-mass sweep."""

    hammer_mass: float
    """M, kg."""
    granule_mass: float
    """m, kg."""
    restitution: float
    """e of the granule-hammer pair (case), -."""
    transfer: float
    dissipated: float
    relative: float
    hammer_frame_loss: float
    """The four ratios of :class:`perga.analytic.impact.ImpactEfficiencies`, measured."""


def efficiency_point(run: Run) -> EfficiencyPoint:
    """The measured efficiencies of a run's first impact."""
    if not run.impacts or not run.impacts["time"].size:
        raise ValueError(f"{run.name}: no impact recorded")
    s = impact_stats(run, 0)
    return EfficiencyPoint(
        hammer_mass=run.case.hammers.mass,
        granule_mass=run.case.granule_mass,
        restitution=run.case.granule_hammer_contact.restitution,
        transfer=s.transfer,
        dissipated=s.dissipated_ratio,
        relative=s.relative,
        hammer_frame_loss=s.normal_loss,
    )
