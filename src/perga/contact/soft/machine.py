"""The machine as soft-contact polygons: the hammers posed from their Pymunk bodies and loaded
back onto them, and a chamber wall drawn from a file (a round wall is the kernel's own circle).

Each convex piece of each hammer becomes one polygon of a
:class:`~perga.contact.soft.polygon_set.PolygonSet` (SI), described relative to its body's
centre of gravity. How a hammer resists a contact sets
the contact's effective mass: a hinged hammer is ``PINNED`` at its hinge with I_A; a welded one
is part of the rotor, ``KINEMATIC`` on a rotor held at ω or ``PINNED`` at the axis with the
rotor's moment on a driven rotor; a free one is ``FREE`` with M and I_C. The wall's pieces
(:meth:`perga.model.system.ChamberSpec.pieces`) come after the hammers' and never move
(``KINEMATIC``, at rest); only the wall's inner and outer outlines make contacts.

Timing (why the pose is taken ahead). Chipmunk's step drifts positions with the current
velocities, then kicks them with the applied forces and joint impulses; the soft kernel kicks,
then drifts. Posing each hammer where Chipmunk's drift will put it one granule step later
(centre of gravity + v·dt, angle + ω·dt) and applying the mean contact force of the granule
steps in the following Chipmunk step makes the two one kick-drift scheme: the force that kicks
a hammer is evaluated at the position it then drifts from, as for the granules (derivation in
docs/architecture.md). Within the granule steps of one machine step the kernel kicks the hammers
by each step's loads; the recoil that gives them is added to the bodies' positions before
Chipmunk's step (``apply_loads``). The joints' position correction (bias velocities, not
exposed by Pymunk) is left out of the prediction: a pose error of the joint's drift,
micrometres.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from perga.contact.soft.polygon_set import FREE, KINEMATIC, PINNED, PolygonSet, polygon_set
from perga.geometry.pieces import piece_features
from perga.geometry.polygon import counter_clockwise
from perga.machine import units as u
from perga.machine.machine import Machine, MachineState, shift_bodies, write_loads

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit."""
FORCE, LENGTH, VELOCITY, ANGULAR_VELOCITY = u.FORCE, u.LENGTH, u.VELOCITY, u.ANGULAR_VELOCITY
"""The units as module globals, which numba freezes into the compiled functions."""


class MachinePolygons:
    """The scene's hammers and drawn chamber wall as a posed ``PolygonSet`` (``self.polygons``):
    every convex piece of every hammer is a polygon, ``hammer_of[k]`` the hammer polygon k
    belongs to (−1 for the wall's pieces, which follow); pieces of one hammer share its body's
    motion and inertia, and only the hammer's outline makes contacts
    (``perga.geometry.pieces.piece_features``).

    ``materials`` lists the polygons' material names (the polygon table's columns).
    """

    def __init__(self, machine: Machine) -> None:
        specs = machine.spec.hammers
        chamber = machine.spec.chamber
        walled = chamber is not None and chamber.outline is not None
        names = {h.material for h in specs} | ({chamber.material} if walled else set())
        self.materials = sorted(names)
        driven = machine.driven
        relative, owner, kinds, inertia, solid, corner = [], [], [], [], [], []
        for index, (h, body, shapes) in enumerate(
            zip(specs, machine.hammer_bodies, machine.hammer_shapes, strict=True)
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
        hinges = np.array(
            [h.hinge_position if h.mount == "hinged" else (0.0, 0.0) for h in specs], dtype=float
        ).reshape(-1, 2)
        self.machine = np.array([k >= 0 and specs[k].mount != "free" for k in owner], dtype=bool)
        """Which polygons the rotor drives (hinged or welded): their loads enter the drive work."""
        rows = machine.hammer_rows  # each hammer's body's row in a MachineState
        self._polygon_rows = rows[self.hammer_of[:n_hammer]]
        """The state row of each hammer polygon's body (the rotor's for a welded hammer)."""
        self._vertex_rows = rows[self._owner]
        """The state row of each hammer vertex's body."""
        self._polygon_hinges = hinges[self.hammer_of[:n_hammer]]
        """Each hammer polygon's pivot in the rotor frame, m ((0, 0) unless hinged)."""
        self._loads = np.zeros((len(machine.bodies), 3))
        """Force and torque on each machine body, internal units (:meth:`apply_loads`)."""
        self._shifts = np.zeros((len(machine.bodies), 3))
        """Each machine body's recoil over the last call, internal units (:meth:`apply_loads`)."""
        leaders = {int(row): k for k, row in reversed(list(enumerate(self._polygon_rows)))}
        body = [leaders[int(row)] for row in self._polygon_rows]
        body += range(n_hammer, len(relative))  # the wall's pieces never move
        self._body_addresses = machine.body_addresses
        self.polygons: PolygonSet = polygon_set(
            relative,
            np.array([p.mean(axis=0) for p in relative]),
            kind=kinds,
            mass=[specs[k].mass if k >= 0 else math.inf for k in owner],
            inertia=inertia,
            mat=materials,
            features=(np.concatenate(solid), np.concatenate(corner)),
            body=body,
        )
        self.pose(0.0, machine.state())

    def pose(self, ahead: float, state: MachineState) -> None:
        """Pose every hammer polygon where its body will be ``ahead`` s after ``state`` at its
        velocity then (positions by v·ahead, angles by ω·ahead), in SI; the wall stays."""
        pose_polygons(state.table, *self.pose_arguments(ahead))

    def pose_arguments(self, ahead: float) -> tuple:
        """The arguments of :func:`pose_polygons` after the state, for :meth:`pose`."""
        p = self.polygons
        return (
            self._polygon_rows, self._vertex_rows, self._relative, self._polygon_hinges, ahead,
            p.vertices, p.com, p.velocity, p.omega, p.pivot,
        )  # fmt: skip

    def apply_loads(self) -> float:
        """Set the polygons' mean loads (from the last kernel call) as the bodies' force and
        torque for the next Pymunk step, and move the bodies by their recoil in the call (the
        kernel kicks the hammers at every granule step; Chipmunk drifts them at the call's start
        velocities and kicks them with the mean loads: with the recoil added, the step lands
        each hammer where the granule steps had it, a multiple-time-step split as in r-RESPA,
        docs/architecture.md); returns the mean moment about the axis on the hammers the rotor
        drives, N·m."""
        return load_bodies(*self.load_arguments())

    def load_arguments(self) -> tuple:
        """The arguments of :func:`load_bodies`, for :meth:`apply_loads`."""
        p = self.polygons
        return (
            p.force, p.torque, p.moment, p.recoil, self._polygon_rows, self.machine, self._loads,
            self._shifts, self._body_addresses(),
        )  # fmt: skip


@numba.njit(cache=True)
def pose_polygons(
    state: np.ndarray,
    polygon_rows: np.ndarray,
    vertex_rows: np.ndarray,
    relative: np.ndarray,
    hinges: np.ndarray,
    ahead: float,
    vertices: np.ndarray,
    com: np.ndarray,
    velocity: np.ndarray,
    omega: np.ndarray,
    pivot: np.ndarray,
) -> None:
    """:meth:`MachinePolygons.pose` in SI from a machine-state table (internal units): vertex j
    of the hammers' polygons is ``relative[j]`` in the frame of its body (state row
    ``vertex_rows[j]``) turned by ω·ahead and carried by v·ahead; polygon k takes its body's
    centre, velocity and ω, and its pivot (``hinges[k]``, rotor frame) turns with the rotor
    (row 0)."""
    length, speed, spin = LENGTH, VELOCITY, ANGULAR_VELOCITY
    for j in range(vertex_rows.size):
        k = vertex_rows[j]
        cx = state[k, 0] * length + state[k, 3] * speed * ahead
        cy = state[k, 1] * length + state[k, 4] * speed * ahead
        angle = state[k, 2] + state[k, 5] * spin * ahead
        c, s = math.cos(angle), math.sin(angle)
        vertices[j, 0] = cx + c * relative[j, 0] - s * relative[j, 1]
        vertices[j, 1] = cy + s * relative[j, 0] + c * relative[j, 1]
    turn = state[0, 2] + state[0, 5] * spin * ahead
    cr, sr = math.cos(turn), math.sin(turn)
    for i in range(polygon_rows.size):
        k = polygon_rows[i]
        com[i, 0] = state[k, 0] * length + state[k, 3] * speed * ahead
        com[i, 1] = state[k, 1] * length + state[k, 4] * speed * ahead
        velocity[i, 0] = state[k, 3] * speed
        velocity[i, 1] = state[k, 4] * speed
        omega[i] = state[k, 5] * spin
        pivot[i, 0] = cr * hinges[i, 0] - sr * hinges[i, 1]
        pivot[i, 1] = sr * hinges[i, 0] + cr * hinges[i, 1]


@numba.njit(cache=True)
def load_bodies(
    force: np.ndarray,
    torque: np.ndarray,
    moment: np.ndarray,
    recoil: np.ndarray,
    polygon_rows: np.ndarray,
    driven: np.ndarray,
    out: np.ndarray,
    shifts: np.ndarray,
    bodies: np.ndarray,
) -> float:
    """Sum the hammer polygons' mean loads (SI) onto their bodies' rows of ``out`` (k, 3:
    force x, y and torque, internal units) and write them into the bodies' structs at the
    addresses ``bodies`` (``Machine.body_addresses``); move each body by its polygons' recoil
    (SI, the same for every polygon of a body; ``shifts`` (k, 3) takes it in internal units);
    returns the mean moment about the axis of the polygons the rotor drives (``driven``, all
    polygons), N·m."""
    out[:] = 0.0
    shifts[:] = 0.0
    for i in range(polygon_rows.size):
        k = polygon_rows[i]
        out[k, 0] += force[i, 0]
        out[k, 1] += force[i, 1]
        out[k, 2] += torque[i]
        shifts[k, 0] = recoil[i, 0] / LENGTH
        shifts[k, 1] = recoil[i, 1] / LENGTH
        shifts[k, 2] = recoil[i, 2]
    for k in range(out.shape[0]):
        out[k, 0] /= FORCE
        out[k, 1] /= FORCE
        out[k, 2] /= TORQUE
    write_loads(bodies, out)
    shift_bodies(bodies, shifts)
    total = 0.0
    for i in range(driven.size):
        if driven[i]:
            total += moment[i]
    return total


def _shifted(corner: np.ndarray, offset: int) -> np.ndarray:
    """``piece_features``' corner rows with their vertex indices (the first two columns, −1 for
    none) moved by ``offset``, for a body whose pieces follow ``offset`` vertices in the set."""
    out = corner.copy()
    ends = out[:, :2]
    ends[ends >= 0] += offset
    return out
