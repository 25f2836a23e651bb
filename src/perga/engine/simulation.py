"""Stepping a :class:`~perga.engine.machine.Scene`, recording impacts, reading state in SI.

Step order of :meth:`Simulation.step` (one Chipmunk ``space.step(dt)``, t_n -> t_{n+1}):

1. The impact recorder's clock is set to t_{n+1} = (n + 1)·dt. Then, only if the spec lists
   them, the kicks (floor friction, air drag: :mod:`perga.engine.effects`) change all granules'
   velocities at once from (x_n, v_n), one batch read and write: an operator split *before*
   Chipmunk's step, so step 2 drifts with the kicked velocities and everything below (contact
   callbacks, the energy meter's reads) sees them; the contacts' impulses (step 4) come after.
2. Chipmunk advances every body's position and angle with its *current* velocity (the
   kinematic rotor turns by ω·dt, so its angle is ω·t exactly up to rounding).
3. Collision detection at the new positions. New granule-hammer contacts call ``begin``: the
   recorder stores the pre-impact relative contact velocity and the granule's and hammer's
   kinetic energies. Restitution and friction are the products of the shapes' values, which
   reproduce the pair table (``scene.factor_pair_table``); only a pair the table cannot split
   has a ``pre_solve`` that sets its exact values.
4. Contacts and joints are pre-stepped (restitution target = e × current approach speed),
   gravity is added to the velocities, the impulse solver runs ``iterations`` times.
5. ``post_solve``: on a pair's first step of contact the recorder completes the
   :class:`Impact` (post-impact velocities, impulse, energy gained and dissipated).
6. The step counter is incremented; ``time`` is n·dt from the integer count (no drift).

With ``track_energy`` an :class:`~perga.engine.energy.EnergyMeter` reads every body's
velocity (``pymunk.batch``) just before ``space.step`` (what ``pre_solve`` in step 3 would see)
and the solved arbiters and the bodies just after it (what ``post_solve`` in step 5 would see),
and balances the rotor-driven bodies' angular momentum around each ``space.step``;
:meth:`Simulation.energy` returns its ledger.

Because positions move before velocities are updated (step 2 before 4), the state after a
step is (x_{n+1}, v_{n+1}) with v_{n+1} computed from the forces at x_{n+1}: symplectic Euler,
first order; in leapfrog terms the velocities are half a step ahead of the positions.
Accessors return the values as Chipmunk holds them, converted to SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pymunk
from numpy.typing import NDArray

from perga.contact.rigid.batch import GranuleReader
from perga.contact.rigid.outline import OutlineFilter
from perga.engine import units as u
from perga.engine.energy import EnergyLedger, EnergyMeter
from perga.engine.machine import Scene
from perga.model.spec import HammerSpec

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Impact:
    """One granule-hammer impact (the first step of a contact), SI units.

    time: s (end of the step in which the contact began); granule, hammer: indices in the
    spec; normal_velocity_before/after: the granule's velocity relative to the hammer's
    material point at the contact, along the hammer's outward normal n (m/s; < 0 approaching,
    > 0 separating); tangential_velocity_before/after: the same along t = n turned +90° (m/s);
    normal_impulse: impulse on the granule along n, N·s (>= 0); point: contact point, m;
    normal: n; granule_energy_gain: change of the granule's kinetic energy (translation and
    spin) over the step, J; dissipated: energy lost in this contact, −J·v̄_rel with v̄_rel the
    mean of the relative contact velocity before and after (exact for one impulse), J;
    hammer_energy_before: the hammer's kinetic energy ½Mv_c² + ½I_cΩ² before the step, J;
    granule_velocity_before: the granule's velocity in the fixed frame before the step, m/s;
    hammer_swing_angle_before, hammer_angular_velocity_before: the hammer's α (rad) and
    absolute angular velocity Ω (rad/s) at the contact's start. Rigid: α after the step's
    position update (Chipmunk moves bodies, then finds contacts), velocities and energies
    before its impulses. Soft (:mod:`~perga.contact.soft.impacts`): the granule's velocity
    before the kernel call in which the contact began, the hammer's state after that step.
    """

    time: float
    granule: int
    hammer: int
    normal_velocity_before: float
    normal_velocity_after: float
    tangential_velocity_before: float
    tangential_velocity_after: float
    normal_impulse: float
    point: tuple[float, float]
    normal: tuple[float, float]
    granule_energy_gain: float
    dissipated: float
    hammer_energy_before: float
    granule_velocity_before: tuple[float, float]
    hammer_swing_angle_before: float
    hammer_angular_velocity_before: float


def _contact(arbiter: pymunk.Arbiter) -> tuple[pymunk.Vec2d, pymunk.Vec2d, pymunk.Vec2d]:
    """Relative velocity granule − hammer at the contact point (internal units), the point and
    the hammer's outward normal. Shapes are ordered (granule, hammer)."""
    granule_shape, hammer_shape = arbiter.shapes
    outward = -arbiter.normal  # arbiter.normal points from the granule to the hammer
    points = arbiter.contact_point_set.points
    p = (points[0].point_a + points[0].point_b) * 0.5
    v_g = granule_shape.body.velocity_at_world_point(p)
    v_h = hammer_shape.body.velocity_at_world_point(p)
    return v_g - v_h, p, outward


def _granule_energy(body: pymunk.Body) -> float:
    """Kinetic energy of a granule body, internal units (a sliding point has moment inf)."""
    spin = 0.0 if math.isinf(body.moment) else 0.5 * body.moment * body.angular_velocity**2
    return 0.5 * body.mass * body.velocity.length_squared + spin


@dataclass(frozen=True)
class HammerState:
    """A hammer now: kinetic energy ½Mv_c² + ½I_cΩ², J; swing angle α, rad; absolute angular
    velocity Ω, rad/s (welded hammers move with the rotor: their α is the spec's)."""

    energy: float
    swing_angle: float
    angular_velocity: float


def hammer_state(scene: Scene, index: int) -> HammerState:
    """The :class:`HammerState` of hammer ``index`` now."""
    spec = scene.spec.hammers[index]
    body = scene.hammer_bodies[index]
    welded = body is scene.rotor
    centre = _welded_com(spec, body) if welded else body.local_to_world(body.center_of_gravity)
    v = body.velocity_at_world_point(centre) * u.VELOCITY
    spin = body.angular_velocity * u.ANGULAR_VELOCITY
    return HammerState(
        energy=0.5 * spec.mass * v.length_squared + 0.5 * spec.moment_about_centre * spin**2,
        swing_angle=spec.swing_angle
        if welded
        else body.angle - scene.rotor.angle - spec.angle_on_rotor,
        angular_velocity=spin,
    )


_Pending = tuple[pymunk.Vec2d, float, pymunk.Vec2d, HammerState]


class ImpactRecorder:
    """Records the first step of every granule-hammer contact as an :class:`Impact`.

    A granule touching two convex pieces of one hammer in the same step (a notch) makes two
    Chipmunk contacts but one impact: their impulses along the first contact's normal and their
    dissipation are summed into the first one's row. With ``filtered`` (hammers of several
    pieces: :mod:`~perga.contact.rigid.outline` drops contacts in ``pre_solve``) an impact
    starts at a contact's first step that is processed, not at its ``begin``.
    """

    def __init__(self, scene: Scene, *, filtered: bool = False) -> None:
        self.impacts: list[Impact] = []
        self.time = 0.0
        self._scene = scene
        self._owner = scene.shape_owner
        # (granule shape, hammer shape) -> relative contact velocity, granule KE and velocity,
        # hammer state (None once recorded); (granule, hammer) -> its impact's row in this step
        self._pending: dict[tuple[pymunk.Shape, pymunk.Shape], _Pending | None] = {}
        self._rows: dict[tuple[int, int], int] = {}
        self._rows_time = -1.0
        start = "pre_solve" if filtered else "begin"
        scene.listen(start, self._start, ("granule", "hammer"))
        scene.on_granule_hammer(post_solve=self._post_solve, separate=self._separate)

    def _key(self, arbiter: pymunk.Arbiter) -> tuple[int, int]:
        granule_shape, hammer_shape = arbiter.shapes
        return self._owner[granule_shape][1], self._owner[hammer_shape][1]

    def _start(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        if not arbiter.process_collision or tuple(arbiter.shapes) in self._pending:
            return
        relative, _, _ = _contact(arbiter)
        body = arbiter.shapes[0].body
        state = hammer_state(self._scene, self._key(arbiter)[1])
        pending = (relative, _granule_energy(body), body.velocity, state)
        self._pending[tuple(arbiter.shapes)] = pending  # type: ignore[index]

    def _post_solve(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        shapes = tuple(arbiter.shapes)
        pending = self._pending.get(shapes)  # type: ignore[call-overload]
        if pending is None:
            return
        self._pending[shapes] = None  # type: ignore[index]
        key = self._key(arbiter)
        before, granule_energy, granule_velocity, hammer = pending
        after, point, n = _contact(arbiter)
        t = n.perpendicular()
        # measured: total_impulse is the impulse on the first shape's body (the granule)
        impulse = arbiter.total_impulse
        joule = u.to_si(1.0, u.ENERGY)
        dissipated = -impulse.dot((before + after) * 0.5) * joule
        if self._rows_time != self.time:
            self._rows, self._rows_time = {}, self.time
        row = self._rows.get(key)
        if row is not None:  # a second piece of the same hammer in the same step
            first = self.impacts[row]
            n_first = pymunk.Vec2d(*first.normal)
            self.impacts[row] = replace(
                first,
                normal_impulse=first.normal_impulse + u.to_si(impulse.dot(n_first), u.IMPULSE),
                dissipated=first.dissipated + dissipated,
            )
            return
        self._rows[key] = len(self.impacts)
        self.impacts.append(
            Impact(
                time=self.time,
                granule=key[0],
                hammer=key[1],
                normal_velocity_before=u.to_si(before.dot(n), u.VELOCITY),
                normal_velocity_after=u.to_si(after.dot(n), u.VELOCITY),
                tangential_velocity_before=u.to_si(before.dot(t), u.VELOCITY),
                tangential_velocity_after=u.to_si(after.dot(t), u.VELOCITY),
                normal_impulse=u.to_si(impulse.dot(n), u.IMPULSE),
                point=u.vec_to_si(tuple(point), u.LENGTH),
                normal=(n.x, n.y),
                granule_energy_gain=(_granule_energy(arbiter.shapes[0].body) - granule_energy)
                * joule,
                dissipated=dissipated,
                hammer_energy_before=hammer.energy,
                granule_velocity_before=u.vec_to_si(tuple(granule_velocity), u.VELOCITY),
                hammer_swing_angle_before=hammer.swing_angle,
                hammer_angular_velocity_before=hammer.angular_velocity,
            )
        )

    def _separate(self, arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
        self._pending.pop(tuple(arbiter.shapes), None)  # type: ignore[arg-type]


class Simulation:
    """Steps a scene at the spec's fixed dt (see the module docstring for the step order).

    record_impacts: keep an :class:`Impact` per granule-hammer impact; track_energy: measure
    the energy ledger from now on (costs two ``pymunk.batch`` body reads and one arbiter read
    per step, no Python callback: :mod:`~perga.engine.energy`).
    """

    def __init__(
        self, scene: Scene, *, record_impacts: bool = True, track_energy: bool = True
    ) -> None:
        self.scene = scene
        self.dt = scene.spec.dt
        self.steps = 0
        self._dt_internal = u.to_internal(self.dt, u.TIME)
        outline = OutlineFilter(scene)  # hammers of several pieces: their outline's contacts
        if outline:
            scene.listen("pre_solve", outline.pre_solve, ("granule", "hammer"))
        filtered = bool(outline)
        self.recorder = ImpactRecorder(scene, filtered=filtered) if record_impacts else None
        self.meter = EnergyMeter(scene) if track_energy else None
        self._reader: GranuleReader | None = None  # built on the first state read

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.steps * self.dt

    @property
    def impacts(self) -> list[Impact]:
        """Impacts recorded so far (empty if recording is off)."""
        return [] if self.recorder is None else self.recorder.impacts

    def step(self) -> None:
        """Advance by one time step dt."""
        if self.recorder is not None:
            self.recorder.time = (self.steps + 1) * self.dt
        for effect in self.scene.effects:  # the kicks (floor friction, air drag), if listed
            effect.before_step(self._dt_internal)
        if self.meter is None:
            self.scene.space.step(self._dt_internal)
        else:
            self.meter.before_step()
            self.scene.space.step(self._dt_internal)
            self.meter.after_step(self._dt_internal)
        self.steps += 1

    def energy(self) -> EnergyLedger:
        """The energy ledger since the simulation was created (J; needs ``track_energy``)."""
        if self.meter is None:
            raise RuntimeError("energy() needs Simulation(..., track_energy=True)")
        return self.meter.ledger()

    def run(self, duration: float) -> int:
        """Advance by ``duration`` (s), rounded to a whole number of steps; returns the count."""
        if not (math.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration must be finite and >= 0 s (got {duration})")
        n = round(duration / self.dt)
        for _ in range(n):
            self.step()
        return n

    # --- state in SI -----------------------------------------------------------------------

    def _granules(self) -> GranuleReader:
        if self._reader is None:
            self._reader = GranuleReader(self.scene)
        return self._reader

    def granule_positions(self) -> FloatArray:
        """Granule centres, (n, 2) array, m (one ``pymunk.batch`` read: :mod:`.state`)."""
        return self._granules().positions()

    def granule_velocities(self) -> FloatArray:
        """Granule centre velocities, (n, 2) array, m/s."""
        return self._granules().velocities()

    def granule_angular_velocities(self) -> FloatArray:
        """Granule angular velocities, (n,) array, rad/s."""
        return self._granules().angular_velocities()

    def rotor_angle(self) -> float:
        """Rotor angle, rad (ω·t at constant ω)."""
        return float(self.scene.rotor.angle)

    def rotor_angular_velocity(self) -> float:
        """Rotor angular velocity, rad/s (varies only with a driven rotor)."""
        return float(self.scene.rotor.angular_velocity) * u.ANGULAR_VELOCITY

    def hammer_swing_angles(self) -> FloatArray:
        """α of each hammer: its axis angle relative to the radial line through the hinge on
        the turning rotor, rad (constant for welded hammers)."""
        hammers = range(len(self.scene.spec.hammers))
        return np.array([hammer_state(self.scene, i).swing_angle for i in hammers], dtype=float)

    def hammer_angular_velocities(self) -> FloatArray:
        """Absolute angular velocity of each hammer, (n,) array, rad/s (welded: the rotor's)."""
        return (
            np.array([b.angular_velocity for b in self.scene.hammer_bodies], dtype=float)
            * u.ANGULAR_VELOCITY
        )

    def hammer_velocities(self) -> FloatArray:
        """Centre-of-mass velocity of each hammer, (n, 2) array, m/s (welded: the rotor's
        velocity at the hammer's centre of mass)."""
        out = []
        for spec, body in zip(self.scene.spec.hammers, self.scene.hammer_bodies, strict=True):
            if body is self.scene.rotor:
                out.append(tuple(body.velocity_at_world_point(_welded_com(spec, body))))
            else:
                out.append(tuple(body.velocity))
        return np.array(out, dtype=float).reshape(-1, 2) * u.VELOCITY


def _welded_com(spec: HammerSpec, rotor: pymunk.Body) -> pymunk.Vec2d:
    """World position (internal units) of a welded hammer's centre of mass."""
    return rotor.local_to_world(u.vec_to_internal(spec.centre_on_rotor, u.LENGTH))
