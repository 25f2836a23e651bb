"""The hammers as soft-contact polygons: posed from their Pymunk bodies, loaded back onto them.

Each convex piece of each hammer becomes one polygon of a :class:`~perga.soft.polygons.PolygonSet`
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
from perga.soft.polygons import FREE, KINEMATIC, PINNED, PolygonSet, piece_features, polygon_set

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit."""


def _counter_clockwise(vertices: np.ndarray) -> np.ndarray:
    x, y = vertices[:, 0], vertices[:, 1]
    area = np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    return vertices if area > 0 else vertices[::-1].copy()


class HammerPolygons:
    """The scene's hammers as a posed ``PolygonSet`` (``self.polygons``): every convex piece of
    every hammer is a polygon, ``hammer_of[k]`` the hammer polygon k belongs to; pieces of one
    hammer share its body's motion and inertia, and only the hammer's outline makes contacts
    (``perga.soft.polygons.piece_features``).

    ``materials`` lists the hammers' material names (the polygon table's columns).
    """

    def __init__(self, scene: Scene) -> None:
        self._scene = scene
        self._bodies = scene.hammer_bodies
        specs = scene.spec.hammers
        self.materials = sorted({h.material for h in specs})
        driven = scene.rotor.body_type == pymunk.Body.DYNAMIC
        relative, owner, kinds, inertia, solid, corner = [], [], [], [], [], []
        for index, (h, body, shapes) in enumerate(
            zip(specs, self._bodies, scene.hammer_shapes, strict=True)
        ):
            cog = body.center_of_gravity
            pieces = [
                _counter_clockwise(np.array([tuple(v - cog) for v in s.get_vertices()]))
                * u.LENGTH
                for s in shapes
            ]
            outline = (np.array(scene.hammer_outlines[index]) - tuple(cog)) * u.LENGTH
            features = piece_features(pieces, [_counter_clockwise(outline)])
            offset = sum(len(r) for r in relative)
            solid.append(features[0])
            corner.append(np.where(features[1] >= 0, features[1] + offset, -1))
            relative += pieces
            owner += [index] * len(pieces)
            if h.mount == "hinged":
                kind, moment = PINNED, h.moment_about_hinge
            elif h.mount == "free":
                kind, moment = FREE, h.moment_about_centre
            elif driven:
                kind, moment = PINNED, body.moment * u.MOMENT
            else:
                kind, moment = KINEMATIC, math.inf
            kinds += [kind] * len(pieces)
            inertia += [moment] * len(pieces)
        self.hammer_of = np.array(owner, dtype=np.int64)
        """The hammer of each polygon."""
        self._relative = np.concatenate(relative)
        self._owner = np.repeat(self.hammer_of, [len(r) for r in relative])
        self._hinges = np.array(
            [h.hinge_position if h.mount == "hinged" else (0.0, 0.0) for h in specs], dtype=float
        ).reshape(-1, 2)
        self.machine = np.array([specs[k].mount != "free" for k in owner], dtype=bool)
        """Which polygons the rotor drives (hinged or welded): their loads enter the drive work."""
        self.polygons: PolygonSet = polygon_set(
            relative,
            np.zeros((len(relative), 2)),
            kind=kinds,
            mass=[specs[k].mass for k in owner],
            inertia=inertia,
            mat=[self.materials.index(specs[k].material) for k in owner],
            features=(np.concatenate(solid), np.concatenate(corner)),
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
        p, of = self.polygons, self.hammer_of
        p.vertices[:, 0] = centre[self._owner, 0] + c * rx - s * ry
        p.vertices[:, 1] = centre[self._owner, 1] + s * rx + c * ry
        p.com[:] = centre[of]
        p.velocity[:] = velocity[of]
        p.omega[:] = omega[of]
        rotor = self._scene.rotor
        turn = rotor.angle + rotor.angular_velocity * u.ANGULAR_VELOCITY * ahead
        cr, sr = math.cos(turn), math.sin(turn)
        hx, hy = self._hinges[of, 0], self._hinges[of, 1]
        p.pivot[:, 0] = cr * hx - sr * hy
        p.pivot[:, 1] = sr * hx + cr * hy

    def apply_loads(self) -> float:
        """Set the polygons' mean loads (from the last kernel call) as the bodies' force and
        torque for the next Pymunk step; returns the mean moment about the axis on the hammers
        the rotor drives, N·m."""
        p = self.polygons
        loads: dict[pymunk.Body, list[float]] = {}
        for k, hammer in enumerate(self.hammer_of):
            load = loads.setdefault(self._bodies[hammer], [0.0, 0.0, 0.0])
            load[0] += p.force[k, 0]
            load[1] += p.force[k, 1]
            load[2] += p.torque[k]
        for body, (fx, fy, torque) in loads.items():
            body.force = (fx / u.FORCE, fy / u.FORCE)
            body.torque = torque / TORQUE
        return float(np.sum(p.moment[self.machine]))
