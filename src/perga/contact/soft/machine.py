"""The machine as soft-contact polygons: the hammers posed from their Pymunk bodies and loaded
back onto them, and a chamber wall drawn from a file (a round wall is the kernel's own circle).

Each convex piece of each hammer becomes one polygon of a
:class:`~perga.contact.soft.polygon_set.PolygonSet` (SI), described relative to its body's
centre of gravity. How a hammer resists a contact sets
the contact's effective mass: a hinged hammer is ``PINNED`` at its hinge with I_A; a welded one
is part of the rotor, ``KINEMATIC`` on a rotor held at ω or ``PINNED`` at the axis with the
rotor's moment on a driven rotor; a free one is ``FREE`` with M and I_C. The wall's pieces
(:meth:`perga.model.spec.ChamberSpec.pieces`) come after the hammers' and never move
(``KINEMATIC``, at rest); only the wall's inner and outer outlines make contacts.

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

from perga.contact.soft.polygon_set import FREE, KINEMATIC, PINNED, PolygonSet, polygon_set
from perga.engine import units as u
from perga.engine.machine import Machine
from perga.geometry.pieces import piece_features
from perga.geometry.polygon import counter_clockwise

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit."""


class MachinePolygons:
    """The scene's hammers and drawn chamber wall as a posed ``PolygonSet`` (``self.polygons``):
    every convex piece of every hammer is a polygon, ``hammer_of[k]`` the hammer polygon k
    belongs to (−1 for the wall's pieces, which follow); pieces of one hammer share its body's
    motion and inertia, and only the hammer's outline makes contacts
    (``perga.geometry.pieces.piece_features``).

    ``materials`` lists the polygons' material names (the polygon table's columns).
    """

    def __init__(self, machine: Machine) -> None:
        self._rotor = machine.rotor
        self._bodies = machine.hammer_bodies
        specs = machine.spec.hammers
        chamber = machine.spec.chamber
        walled = chamber is not None and chamber.outline is not None
        names = {h.material for h in specs} | ({chamber.material} if walled else set())
        self.materials = sorted(names)
        driven = machine.driven
        relative, owner, kinds, inertia, solid, corner = [], [], [], [], [], []
        for index, (h, body, shapes) in enumerate(
            zip(specs, self._bodies, machine.hammer_shapes, strict=True)
        ):
            cog = body.center_of_gravity
            pieces = [
                counter_clockwise(np.array([tuple(v - cog) for v in s.get_vertices()])) * u.LENGTH
                for s in shapes
            ]
            outline = (np.array(machine.hammer_outlines[index]) - tuple(cog)) * u.LENGTH
            features = piece_features(pieces, [counter_clockwise(outline)])
            offset = sum(len(r) for r in relative)
            solid.append(features[0])
            corner.append(_shifted(features[1], offset))
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
        self._relative = np.concatenate(relative) if relative else np.zeros((0, 2))
        self._owner = np.repeat(np.array(owner, dtype=np.int64), [len(r) for r in relative])
        n_hammer = len(relative)
        materials = [self.materials.index(specs[k].material) for k in owner]
        if walled:
            pieces, outer = chamber.pieces()
            loops = [outer, chamber.inner_outline()[::-1]]
            features = piece_features(pieces, loops)
            offset = len(self._relative)
            solid.append(features[0])
            corner.append(_shifted(features[1], offset))
            relative += pieces
            owner += [-1] * len(pieces)
            kinds += [KINEMATIC] * len(pieces)
            inertia += [math.inf] * len(pieces)
            materials += [self.materials.index(chamber.material)] * len(pieces)
        self.hammer_of = np.array(owner, dtype=np.int64)
        """The hammer of each polygon (−1: the wall)."""
        self._hammer_polygons = n_hammer
        self._hammer_vertices = len(self._relative)
        self._hinges = np.array(
            [h.hinge_position if h.mount == "hinged" else (0.0, 0.0) for h in specs], dtype=float
        ).reshape(-1, 2)
        self.machine = np.array([k >= 0 and specs[k].mount != "free" for k in owner], dtype=bool)
        """Which polygons the rotor drives (hinged or welded): their loads enter the drive work."""
        self.polygons: PolygonSet = polygon_set(
            relative,
            np.array([p.mean(axis=0) for p in relative]),
            kind=kinds,
            mass=[specs[k].mass if k >= 0 else math.inf for k in owner],
            inertia=inertia,
            mat=materials,
            features=(np.concatenate(solid), np.concatenate(corner)),
        )
        self.pose(0.0)

    def pose(self, ahead: float) -> None:
        """Pose every hammer polygon where its body will be ``ahead`` s from now at its current
        velocity (positions by v·ahead, angles by ω·ahead), in SI; the wall stays."""
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
        p, of, n = self.polygons, self.hammer_of[: self._hammer_polygons], self._hammer_vertices
        p.vertices[:n, 0] = centre[self._owner, 0] + c * rx - s * ry
        p.vertices[:n, 1] = centre[self._owner, 1] + s * rx + c * ry
        p.com[: len(of)] = centre[of]
        p.velocity[: len(of)] = velocity[of]
        p.omega[: len(of)] = omega[of]
        rotor = self._rotor
        turn = rotor.angle + rotor.angular_velocity * u.ANGULAR_VELOCITY * ahead
        cr, sr = math.cos(turn), math.sin(turn)
        hx, hy = self._hinges[of, 0], self._hinges[of, 1]
        p.pivot[: len(of), 0] = cr * hx - sr * hy
        p.pivot[: len(of), 1] = sr * hx + cr * hy

    def apply_loads(self) -> float:
        """Set the polygons' mean loads (from the last kernel call) as the bodies' force and
        torque for the next Pymunk step; returns the mean moment about the axis on the hammers
        the rotor drives, N·m."""
        p = self.polygons
        loads: dict[pymunk.Body, list[float]] = {}
        for k, hammer in enumerate(self.hammer_of[: self._hammer_polygons]):
            load = loads.setdefault(self._bodies[hammer], [0.0, 0.0, 0.0])
            load[0] += p.force[k, 0]
            load[1] += p.force[k, 1]
            load[2] += p.torque[k]
        for body, (fx, fy, torque) in loads.items():
            body.force = (fx / u.FORCE, fy / u.FORCE)
            body.torque = torque / TORQUE
        return float(np.sum(p.moment[self.machine]))


def _shifted(corner: np.ndarray, offset: int) -> np.ndarray:
    """``piece_features``' corner rows with their vertex indices (the first two columns, −1 for
    none) moved by ``offset``, for a body whose pieces follow ``offset`` vertices in the set."""
    out = corner.copy()
    ends = out[:, :2]
    ends[ends >= 0] += offset
    return out
