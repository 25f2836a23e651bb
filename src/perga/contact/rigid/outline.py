"""Rigid contacts with hammers of several convex pieces: only the hammer's outline counts.

Chipmunk collides a granule with each convex piece on its own, so near a seam between two
pieces it makes contacts that the hammer's outline does not have: with the seam itself (a
"ghost" normal along the diagonal) and with a corner split between two pieces (blended
normals; docs/dev/validation.md has what that does to a rebound). ``OutlineFilter`` gives every
Chipmunk contact of such a hammer, in ``pre_solve``, the contact of the soft kernel's rule
(:func:`perga.geometry.disc_polygon.closest_feature` over the piece's solid edges and owned
corners): a piece whose feature is not the outline's, or that the granule does not overlap by
the outline's rule, has no contact this step; the others get the outline's normal and depth.
Scenes with convex hammers only install nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pymunk

from perga.geometry.disc_polygon import closest_feature
from perga.geometry.pieces import outline_arrays
from perga.geometry.polygon import counter_clockwise
from perga.machine import units as u
from perga.machine.machine import Machine


class OutlineFilter:
    """The pieces of the machine's multi-piece hammers in their bodies' frames (SI), with the
    outline features of :func:`~perga.geometry.pieces.outline_arrays`."""

    def __init__(self, machine: Machine) -> None:
        self._piece: dict[pymunk.Shape, tuple[tuple[np.ndarray, ...], int]] = {}
        for shapes, outline in zip(machine.hammer_shapes, machine.hammer_outlines, strict=True):
            if len(shapes) < 2:
                continue
            pieces = [counter_clockwise(np.array(s.get_vertices()) * u.LENGTH) for s in shapes]
            loop = counter_clockwise(np.array(outline) * u.LENGTH)
            arrays = outline_arrays(pieces, [loop])
            for k, shape in enumerate(shapes):
                self._piece[shape] = (arrays, k)

    def __bool__(self) -> bool:
        return bool(self._piece)

    def pre_solve(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: Any) -> None:
        """Replace a granule-hammer contact (shapes granule, hammer) by the outline's, or drop
        it for this step."""
        granule, hammer = arbiter.shapes
        piece = self._piece.get(hammer)
        if piece is None:
            return
        body = hammer.body
        centre = granule.body.position
        x, y = body.world_to_local(centre) * u.LENGTH
        d, nx, ny = closest_feature(x, y, *piece[0], piece[1])
        d = d / u.LENGTH
        r = granule.radius
        if not d < r:  # not the outline's feature, or not touching it
            arbiter.process_collision = False
            return
        arbiter.process_collision = True  # the flag stays as set: a rejected step leaves it off
        outward = pymunk.Vec2d(nx, ny).rotated(body.angle)  # from the hammer to the granule
        point = pymunk.ContactPoint(centre - outward * r, centre - outward * d, d - r)
        arbiter.contact_point_set = pymunk.ContactPointSet(-outward, (point,))
