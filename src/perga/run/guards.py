"""What a run checks of every frame before it is written: finite states, granules inside the
wall, and every granule fed accounted for."""

from __future__ import annotations

import numpy as np

from perga.model.frame import Frame


class RunStoppedError(Exception):
    """The simulation cannot go on; the message names the step, the granule and a remedy."""


def check_granules(frame: Frame, chamber_radius: float, wall_thickness: float, dt: float) -> None:
    """Raise RunStoppedError for a non-finite state or a granule outside the chamber wall
    (farther from the axis than the wall's farthest inner point, ``chamber_radius``, plus its
    thickness); ``dt`` (s) is named in the remedy."""
    p, v = frame.granules.positions, frame.granules.velocities
    ids = frame.granules.ids
    bad = np.nonzero(~np.all(np.isfinite(np.hstack((p, v))), axis=1))[0]
    if bad.size:
        raise RunStoppedError(
            f"step {frame.step} (t = {frame.time:.6g} s): granule {ids[bad[0]]} has a non-finite "
            f"position or velocity; reduce solver.dt (now {dt:.3g} s)"
        )
    r = np.hypot(p[:, 0], p[:, 1])
    out = np.nonzero(r > chamber_radius + wall_thickness)[0]
    if out.size:
        i = out[0]
        raise RunStoppedError(
            f"step {frame.step} (t = {frame.time:.6g} s): granule {ids[i]} left the chamber "
            f"(r = {r[i]:.4g} m > wall at {chamber_radius:g} m + {wall_thickness:g} m): it "
            f"tunnelled through the wall; reduce solver.dt (now {dt:.3g} s) or increase "
            "chamber.wall_thickness"
        )


def check_population(frame: Frame) -> None:
    """Raise RunStoppedError unless every granule fed is present, departed or removed broken."""
    present = len(frame.granules.ids)
    if frame.fed != present + frame.departed + frame.removed_broken:
        raise RunStoppedError(
            f"step {frame.step} (t = {frame.time:.6g} s): granules not conserved: {frame.fed} "
            f"fed != {present} present + {frame.departed} departed + {frame.removed_broken} "
            "removed broken (a defect of perga: please report it with the case file)"
        )
