"""Rigid granule-wall impacts under in-plane gravity kept to the impulse law: the height after a
bounce is e² times the height before.

Chipmunk's step is semi-implicit Euler (positions with the step's starting velocity v_k, then
v += g·dt, then the impulses). It finds a new contact up to |v|·dt inside the wall, sets the
normal velocity to e·|v_k| (the velocity before gravity's kick of that step), and then pushes the
granule out of the wall through its position (the bias), its velocity untouched. Under gravity
that push lifts the granule for nothing: on a flat floor bounce heights climb above h0·e^(2n).

In free flight under a constant g, semi-implicit Euler steps the granule exactly along the
parabola whose velocity at each step is u = v − ½g·dt, so along a wall's normal n (gap s,
g_n = g·n) it conserves H = ½u_n² − g_n·s. At the first step of a granule-wall contact, when the
granule was clear of the wall at the step's start (s_k = s_{k+1} − v_n·dt ≥ 0) and approaching
it: it touched at speed |u_t| = √(u_k² − 2g_n·s_k) and leaves at e·|u_t|; the normal velocity
after the step is the one that gives the granule, where the step left it (s_{k+1} < 0), that
energy: u = √(e²u_t² + 2g_n·s_{k+1}), v = u + ½g_n·dt. Chipmunk gets it as the arbiter's
restitution (its bounce is the restitution times the step's starting normal velocity) and the
contact's distance as 0 (no push follows). The friction impulse is Chipmunk's. Heights after
each bounce then follow e² to round-off (docs/dev/validation.md has the figures before and after).
"""

from __future__ import annotations

import math
from typing import Any

import pymunk


def wall_bounce(arbiter: pymunk.Arbiter, space: pymunk.Space, _data: Any) -> None:
    """``pre_solve`` of granule-wall contacts (shapes granule, wall): at a contact's first step,
    the restitution and distance above; other steps, and contacts begun inside the wall or
    not approaching it, are left to Chipmunk."""
    if not arbiter.is_first_contact:
        return
    points = arbiter.contact_point_set.points
    if len(points) != 1:
        return
    normal = -arbiter.normal  # from the wall to the granule
    v = arbiter.shapes[0].body.velocity.dot(normal)
    dt = space.current_time_step
    gap = points[0].distance
    if v >= 0 or gap - v * dt < 0:
        return
    g = space.gravity.dot(normal)
    u = v - 0.5 * g * dt
    touch = u * u - 2.0 * g * (gap - v * dt)  # u_t², internal units
    after = arbiter.restitution**2 * touch + 2.0 * g * gap
    if after <= 0.0:
        return
    v_after = math.sqrt(after) + 0.5 * g * dt
    if v_after <= 0.0:  # gravity's kick over the step exceeds the rebound: Chipmunk's rest
        return
    arbiter.restitution = v_after / -v
    a = points[0].point_a
    arbiter.contact_point_set = pymunk.ContactPointSet(
        arbiter.normal, [pymunk.ContactPoint(a, a, 0.0)]
    )
