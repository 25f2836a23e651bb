"""What a granule may not overlap at t = 0: the hammers, posed as the case puts them, and the
chamber (its drawn inner outline, or its circle), as :class:`perga.geometry.clearance.Obstacles`."""

from __future__ import annotations

import math

import numpy as np

from perga.case.schema import Case
from perga.geometry.clearance import Obstacles
from perga.model.hammer_geometry import hammer_geometry
from perga.model.parts import chamber_geometry, hammer_angles, hinge_positions


def hammer_outlines(case: Case) -> list[np.ndarray]:
    """Each hammer's outline in the fixed frame at t = 0, m."""
    outline = np.asarray(hammer_geometry(case).outline, dtype=float)
    out = []
    for (hx, hy), phi in zip(hinge_positions(case), hammer_angles(case), strict=True):
        a = phi + case.hammers.swing_angle
        c, s = math.cos(a), math.sin(a)
        out.append(
            np.column_stack(
                (
                    hx + c * outline[:, 0] - s * outline[:, 1],
                    hy + s * outline[:, 0] + c * outline[:, 1],
                )
            )
        )
    return out


def initial_obstacles(case: Case) -> Obstacles:
    """The hammers at t = 0 and the chamber of ``case`` (no container without a chamber)."""
    wall = chamber_geometry(case)
    if wall is None:
        return Obstacles(hammer_outlines(case))
    if wall.outline is None:
        return Obstacles(hammer_outlines(case), container_radius=wall.inner_radius)
    return Obstacles(hammer_outlines(case), container=np.asarray(wall.outline, dtype=float))
