"""Contacts of a sliding point (``granules.rolls = false``): a granule that does not roll is a
point at its centre, whatever its radius, as in :mod:`perga.analytic.sliding`.

Its body has an infinite moment: its spin never changes (0 in the fixed frame), so its own
velocity is its centre's everywhere. Chipmunk takes a contact's relative velocity at the other
body's surface point, r from the centre: on a hammer face turning at ω the granule slipped at
x′ − ω·r (as if it had the spin −ω relative to the face, which it may not have), and from rest
on a leading face friction pushed it outwards until x′ > ω·r. In ``pre_solve`` such a contact
is moved onto the point: the other body's contact point to the granule's centre plus the
contact's distance along the normal (Chipmunk's distance, and with it the push-out, unchanged).
The slip is then the centre's velocity relative to the other body's material at the centre
(x′ along a face turning at ω), and the other body takes the impulse there, so that what
friction dissipates is what the two bodies lose. Walls do not move and two sliding points have
uniform velocity fields: their contacts need nothing.
"""

from __future__ import annotations

import math
from typing import Any

import pymunk


def _slides(shape: pymunk.Shape) -> bool:
    return math.isinf(shape.body.moment)


def _onto(arbiter: pymunk.Arbiter, granule: pymunk.Shape, sign: float) -> None:
    """Each contact point of ``arbiter`` onto ``granule``'s centre: its own point there, the
    other's ``sign``·distance along the normal from it (+1: the granule is the first shape)."""
    normal = arbiter.normal
    centre = granule.body.position
    points = []
    for p in arbiter.contact_point_set.points:
        other = centre + normal * (sign * p.distance)
        a, b = (centre, other) if sign > 0 else (other, centre)
        points.append(pymunk.ContactPoint(a, b, p.distance))
    arbiter.contact_point_set = pymunk.ContactPointSet(normal, points)


def hammer_contact(arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: Any) -> None:
    """``pre_solve`` of granule-hammer contacts: a sliding point's contact onto its centre."""
    granule = arbiter.shapes[0]
    if _slides(granule):
        _onto(arbiter, granule, 1.0)


def granule_contact(arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: Any) -> None:
    """``pre_solve`` of granule-granule contacts: where one of the two is a sliding point, the
    contact onto its centre."""
    a, b = arbiter.shapes
    if _slides(a) and not _slides(b):
        _onto(arbiter, a, 1.0)
    elif _slides(b) and not _slides(a):
        _onto(arbiter, b, -1.0)
