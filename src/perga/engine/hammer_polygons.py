"""The hammers as soft-contact polygons: posed from their Pymunk bodies, loaded back onto them.

Each hammer's convex outline becomes one polygon of a :class:`~perga.soft.polygons.PolygonSet`
(SI), described relative to its body's centre of gravity. How a hammer resists a contact sets
the contact's effective mass: a hinged hammer is ``PINNED`` at its hinge with I_A; a welded one
is part of the rotor, ``KINEMATIC`` on a rotor held at ω or ``PINNED`` at the axis with the
rotor's moment on a driven rotor; a free one is ``FREE`` with M and I_C.

Timing (why the pose is taken ahead). Chipmunk's step drifts positions with the current
velocities, then kicks them with the applied forces and joint impulses; the soft kernel kicks,
then drifts. Posing each hammer where Chipmunk's drift will put it one granule step later
(centre of gravity + v·dt, angle + ω·dt) and applying the mean contact force of the granule
steps in the following Chipmunk step makes the two one kick-drift scheme: the force that kicks
a hammer is evaluated at the position it then drifts from, as for the granules (derivation in
docs/architecture.md). The joints' position correction (bias velocities, not exposed by
Pymunk) is left out of the prediction: a pose error of the joint's drift, micrometres.
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from perga.engine import units as u
from perga.engine.scene import Scene
from perga.soft.polygons import FREE, KINEMATIC, PINNED, PolygonSet, polygon_set

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit."""


def _counter_clockwise(vertices: np.ndarray) -> np.ndarray:
    x, y = vertices[:, 0], vertices[:, 1]
    area = np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return vertices if area > 0 else vertices[::-1].copy()


class HammerPolygons:
    """The scene's hammers as a posed ``PolygonSet`` (``self.polygons``), polygon i = hammer i.

    ``materials`` lists the hammers' material names (the polygon table's columns).
    """

    def __init__(self, scene: Scene) -> None:
        self._scene = scene
        self._bodies = scene.hammer_bodies
        specs = scene.spec.hammers
        self.materials = sorted({h.material for h in specs})
        driven = scene.rotor.body_type == pymunk.Body.DYNAMIC
        relative, kinds, mass, inertia = [], [], [], []
        for h, body, shape in zip(specs, self._bodies, scene.hammer_shapes, strict=True):
            cog = body.center_of_gravity
            local = np.array([tuple(v - cog) for v in shape.get_vertices()]) * u.LENGTH
            relative.append(_counter_clockwise(local))
            if h.mount == "hinged":
                kinds.append(PINNED)
                inertia.append(h.moment_about_hinge)
            elif h.mount == "free":
                kinds.append(FREE)
                inertia.append(h.moment_about_centre)
            elif driven:
                kinds.append(PINNED)
                inertia.append(body.moment * u.MOMENT)
            else:
                kinds.append(KINEMATIC)
                inertia.append(math.inf)
            mass.append(h.mass)
        self._relative = np.concatenate(relative)
        self._owner = np.repeat(np.arange(len(relative)), [len(r) for r in relative])
        self._hinges = np.array(
            [h.hinge_position if h.mount == "hinged" else (0.0, 0.0) for h in specs], dtype=float
        ).reshape(-1, 2)
        self.machine = np.array([h.mount != "free" for h in specs], dtype=bool)
        """Which hammers the rotor drives (hinged or welded): their loads enter the drive work."""
        self.polygons: PolygonSet = polygon_set(
            relative,
            np.zeros((len(relative), 2)),
            kind=kinds,
            mass=mass,
            inertia=inertia,
            mat=[self.materials.index(h.material) for h in specs],
        )
        self.pose(0.0)

    def pose(self, ahead: float) -> None:
        """Pose every polygon where its body will be ``ahead`` s from now at its current
        velocity (positions by v·ahead, angles by ω·ahead), in SI."""
        state = np.array(
            [
                (*b.local_to_world(b.center_of_gravity), b.angle, *b.velocity, b.angular_velocity)
                for b in self._bodies
            ],
            dtype=float,
        ).reshape(-1, 6)
        centre = state[:, 0:2] * u.LENGTH
        velocity = state[:, 3:5] * u.VELOCITY
        omega = state[:, 5] * u.ANGULAR_VELOCITY
        centre = centre + velocity * ahead
        angle = state[:, 2] + omega * ahead
        c, s = np.cos(angle)[self._owner], np.sin(angle)[self._owner]
        rx, ry = self._relative[:, 0], self._relative[:, 1]
        p = self.polygons
        p.vertices[:, 0] = centre[self._owner, 0] + c * rx - s * ry
        p.vertices[:, 1] = centre[self._owner, 1] + s * rx + c * ry
        p.com[:] = centre
        p.velocity[:] = velocity
        p.omega[:] = omega
        rotor = self._scene.rotor
        turn = rotor.angle + rotor.angular_velocity * u.ANGULAR_VELOCITY * ahead
        cr, sr = math.cos(turn), math.sin(turn)
        hx, hy = self._hinges[:, 0], self._hinges[:, 1]
        p.pivot[:, 0] = cr * hx - sr * hy
        p.pivot[:, 1] = sr * hx + cr * hy

    def apply_loads(self) -> float:
        """Set the polygons' mean loads (from the last kernel call) as the bodies' force and
        torque for the next Pymunk step; returns the mean moment about the axis on the hammers
        the rotor drives, N·m."""
        p = self.polygons
        loads: dict[pymunk.Body, list[float]] = {}
        for k, body in enumerate(self._bodies):
            load = loads.setdefault(body, [0.0, 0.0, 0.0])
            load[0] += p.force[k, 0]
            load[1] += p.force[k, 1]
            load[2] += p.torque[k]
        for body, (fx, fy, torque) in loads.items():
            body.force = (fx / u.FORCE, fy / u.FORCE)
            body.torque = torque / TORQUE
        return float(np.sum(p.moment[self.machine]))
