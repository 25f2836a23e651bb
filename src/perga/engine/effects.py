"""Optional physics, built by :func:`~perga.engine.machine.build_scene` only when the spec lists
it (design §3): an absent effect leaves no per-step hook, constraint or callback.

Each effect is a class registered under its :class:`~perga.model.spec.EffectsSpec` field name.
Effects that act on granule velocities (floor friction, air drag) are *kicks*: array operations
on all granules at once, with no per-granule Python. Once per step, **before** Chipmunk's
``space.step`` (:meth:`Effect.before_step`, called by :meth:`~perga.engine.simulation.
Simulation.step`), one :class:`~perga.contact.rigid.batch.GranuleWriter` reads every granule's
velocity (and position, for the co-rotating floor) in one ``pymunk.batch`` pass, every listed kick
changes the velocity arrays in registry order, each a velocity change over dt that never
reverses the velocity it opposes, and one batch write sets them (every other body keeps its
velocity bit for bit). The granules keep Chipmunk's default velocity function (gravity).
Effects that are constraints (hinge friction, drive) are pymunk motors.

Where the kick sits (an operator split). Chipmunk's step is drift (positions with the current
velocities), collision detection, then gravity and the contact/joint impulses. The kicks used
to run inside the step, after the drift, as a velocity function; they now run before the
step, so a step is kick (at x_n, v_n), drift (with the kicked velocity), solve. Both are first
order in dt; the kick now sees the position at the start of the step rather than the drifted
one, and it is applied before, not after, the restitution targets of the step's contacts are
taken (so an impact's approach speed includes the step's friction and drag). Measured effect
on the closed forms (tests/engine/test_closed_forms.py, tests/engine/test_energy.py), relative
errors inside the step / before the step: the co-rotating floor on a blade (BladeSlide) exit
time 5.0e-5 / 6.0e-5 and exit speed −8.8e-5 / −7.4e-5 at dt = 5e-6 s (8.5e-5 / 1.05e-4 and
−1.6e-4 / −1.3e-4 at 1e-5 s: still first order); a granule stopping on the stationary floor
(dt = 1e-4 s) travels v²/(2μg) · (1 + 2.0e-4) / (1 − 2.0e-4) (x_{n+1} = x_n + v'_n dt with the
kicked v'_n), and its friction equals the initial kinetic energy to rounding (1.8e-15) either
way; air drag's velocities are exact either way (the kick integrates dv/dt = −k|v|v exactly
over dt), its distance ln(1 + k v0 t)/k is off by +4.4e-5 / −4.4e-5 at 1e-4 s.

Energy: every effect counts, in J, the energy it removed (``removed`` >= 0) and the work the
rotor did through it (``supplied``, only the co-rotating floor), each from its own kicks or
impulses, never from a global balance. The ledger (:mod:`perga.engine.energy`) sums them by
``term``. A kick's energy is the exact change it made, granule by granule, summed over the
granules in numpy (so only the summation order differs from a per-granule loop).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
import pymunk
from numpy.typing import NDArray

from perga.contact.rigid.batch import GranuleWriter
from perga.engine import units as u
from perga.model.spec import AirDragSpec, DriveSpec, FloorFrictionSpec

if TYPE_CHECKING:
    from perga.engine.machine import Scene

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit (1e-3)."""

Term = Literal["friction", "drag", "drive", "contact"]
FloatArray = NDArray[np.float64]


class Effect:
    """Base of all effects: the ledger term its removed energy belongs to, and its counters
    (kept in internal energy units, read in J)."""

    name: ClassVar[str]
    term: ClassVar[Term]

    def __init__(self) -> None:
        self._removed = 0.0
        self._supplied = 0.0

    @property
    def removed(self) -> float:
        """Energy this effect has taken out of the bodies since t = 0, J (>= 0)."""
        return self._removed * u.ENERGY

    @property
    def supplied(self) -> float:
        """Work the rotor has done on the bodies through this effect since t = 0, J."""
        return self._supplied * u.ENERGY

    def before_step(self, dt: float) -> None:
        """Called by ``Simulation.step`` before every ``space.step`` (``dt`` internal units).
        Does nothing unless the effect is the kick that runs the step's kicks."""


class Kick(Effect):
    """An effect that changes all granules' velocities once per step, before ``space.step``,
    as array operations (module docstring). :func:`build_effects` gives the first kick of a
    scene the shared :class:`_Kicks` runner; the others are run by it."""

    def __init__(self) -> None:
        super().__init__()
        self.needs_positions = False
        """Whether :meth:`kick` needs the granules' positions."""
        self._runner: _Kicks | None = None

    def before_step(self, dt: float) -> None:
        if self._runner is not None:
            self._runner.run(dt)

    def kick(self, velocities: FloatArray, positions: FloatArray | None, dt: float) -> FloatArray:
        """The granules' velocities after one step of ``dt`` of this effect (internal units;
        rows in spec order; ``positions`` given if :attr:`needs_positions`). Counts the energy
        and must not change its arguments."""
        raise NotImplementedError


class _Kicks:
    """Runs a scene's kicks: one batch read, each kick in registry order, one batch write."""

    def __init__(self, scene: Scene, kicks: list[Kick]) -> None:
        self.kicks = kicks
        self.writer = GranuleWriter(scene)
        self._positions = any(k.needs_positions for k in kicks)

    def run(self, dt: float) -> None:
        if self.writer.count == 0:
            return
        velocities, positions = self.writer.read_internal(positions=self._positions)
        self.writer.write_internal_velocities(run_kicks(self.kicks, velocities, positions, dt))


def run_kicks(
    kicks: list[Kick], velocities: FloatArray, positions: FloatArray | None, dt: float
) -> FloatArray:
    """The granules' velocities after every kick in ``kicks``, in order (internal units)."""
    for effect in kicks:
        velocities = effect.kick(velocities, positions, dt)
    return velocities


def _speeds(v: FloatArray) -> FloatArray:
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1])


def _granule_masses(scene: Scene) -> FloatArray:
    """Granule masses, internal units, spec order (the granules' bodies hold the same values)."""
    return np.array([u.to_internal(g.mass, u.MASS) for g in scene.spec.granules], dtype=np.float64)


_REGISTRY: dict[str, Callable[[Scene, Any], Effect]] = {}


def _register(cls: type[Effect]) -> type[Effect]:
    _REGISTRY[cls.name] = cls
    return cls


@_register
class Drive(Effect):
    """The rotor becomes a dynamic body of the spec's inertia (plus the welded hammers' moments
    about the axis), pinned to the static body at the axis and driven by
    ``SimpleMotor(rotor, static_body, ω)`` (this order turns it forward, design §5) whose
    ``max_force`` is the torque limit. The rotor's mass (it only loads the axis pin) is that of
    a uniform disc of the rotor radius with the given inertia, plus the welded hammers'; its
    centre of mass stays on the axis. The motor's work is measured by the energy meter from
    the rotor's angular momentum balance, not here."""

    name = "drive"
    term = "drive"

    def __init__(self, scene: Scene, spec: DriveSpec) -> None:
        super().__init__()
        welded = [h for h in scene.spec.hammers if h.mount == "welded"]
        moment = spec.inertia + sum(
            h.moment_about_centre + h.mass * (h.centre_on_rotor[0] ** 2 + h.centre_on_rotor[1] ** 2)
            for h in welded
        )
        mass = 2 * spec.inertia / scene.spec.rotor.radius**2 + sum(h.mass for h in welded)
        rotor, static = scene.rotor, scene.space.static_body
        omega = rotor.angular_velocity
        rotor.body_type = pymunk.Body.DYNAMIC
        rotor.mass = u.to_internal(mass, u.MASS)
        rotor.moment = u.to_internal(moment, u.MOMENT)
        rotor.angular_velocity = omega
        self.pivot = pymunk.PivotJoint(rotor, static, (0.0, 0.0))
        self.motor = pymunk.SimpleMotor(rotor, static, omega)
        self.motor.max_force = u.to_internal(spec.torque_limit, TORQUE)
        scene.space.add(self.pivot, self.motor)


class _AngularImpulseLosses(Effect):
    """An effect whose constraints act on the relative rotation of two bodies, removing per step
    |j|·|ω̄_rel|: the constraint's angular impulse times the mean of the relative angular
    velocity before and after the step (exact for one impulse on a pair of bodies)."""

    def __init__(self) -> None:
        super().__init__()
        self._before: dict[pymunk.Constraint, float] = {}

    def _watch(self, constraint: pymunk.Constraint) -> None:
        constraint.pre_solve = self._pre_solve
        constraint.post_solve = self._post_solve

    @staticmethod
    def _relative(constraint: pymunk.Constraint) -> float:
        return constraint.b.angular_velocity - constraint.a.angular_velocity

    def _pre_solve(self, constraint: pymunk.Constraint, _space: pymunk.Space) -> None:
        self._before[constraint] = self._relative(constraint)

    def _post_solve(self, constraint: pymunk.Constraint, _space: pymunk.Space) -> None:
        mean = 0.5 * (self._before[constraint] + self._relative(constraint))
        self._removed += constraint.impulse * abs(mean)


@_register
class HingeFriction(_AngularImpulseLosses):
    """Coulomb friction torque at every hinge: per hinged hammer a ``SimpleMotor(hammer,
    rotor, 0)`` with ``max_force`` = the torque (Chipmunk's joint-friction idiom); its losses
    as :class:`_AngularImpulseLosses`."""

    name = "hinge_friction"
    term = "friction"

    def __init__(self, scene: Scene, torque: float) -> None:
        super().__init__()
        self.motors: list[pymunk.SimpleMotor] = []
        for joint in scene.joints:
            motor = pymunk.SimpleMotor(joint.b, joint.a, 0.0)
            motor.max_force = u.to_internal(torque, TORQUE)
            motor.collide_bodies = False
            self._watch(motor)
            scene.space.add(motor)
            self.motors.append(motor)


class SwingStops(_AngularImpulseLosses):
    """The stops of hinged hammers (``RotaryLimitJoint``, built by the scene when a hammer has
    a ``swing_limit``): a hammer swinging into its stop is stopped by a perfectly inelastic
    angular impulse, whose losses (:class:`_AngularImpulseLosses`) count with the contacts'
    dissipation. Not in the registry: built for the hammers that have stops, not from
    ``EffectsSpec``."""

    name = "swing_stops"
    term = "contact"

    def __init__(self, stops: list[pymunk.RotaryLimitJoint]) -> None:
        super().__init__()
        for stop in stops:
            self._watch(stop)


@_register
class FloorFriction(Kick):
    """Coulomb floor friction under a horizontal rotor: a velocity change of at most μ g dt
    opposing the granule's velocity relative to the floor (ω × r for the co-rotating floor,
    ω the rotor's angular velocity and r the granule's position at the start of the step; zero
    for the stationary one), clamped so that the relative velocity stops rather than reverses.

    A kick from v to v' with floor velocity w removes ½m(|v − w|² − |v' − w|²) and the
    floor does work m(v' − v)·w (the rotor's share). On a driven rotor the floor's reaction
    torque is not applied to the rotor (a limitation)."""

    name = "floor_friction"
    term = "friction"

    def __init__(self, scene: Scene, spec: FloorFrictionSpec) -> None:
        super().__init__()
        self._deceleration = u.to_internal(spec.friction * spec.gravity, u.ACCELERATION)
        self._rotor = scene.rotor if spec.floor == "corotating" else None
        self.needs_positions = self._rotor is not None
        self._mass = _granule_masses(scene)

    def kick(self, velocities: FloatArray, positions: FloatArray | None, dt: float) -> FloatArray:
        if self._rotor is None:
            floor = np.zeros_like(velocities)
            relative = velocities
        else:
            assert positions is not None
            w = self._rotor.angular_velocity
            floor = np.empty_like(velocities)
            floor[:, 0] = -w * positions[:, 1]
            floor[:, 1] = w * positions[:, 0]
            relative = velocities - floor
        speed = _speeds(relative)
        moving = speed > 0.0
        safe = np.where(moving, speed, 1.0)
        scale = np.where(moving, 1.0 - np.minimum(self._deceleration * dt, speed) / safe, 1.0)
        after = relative * scale[:, None]
        new = np.where(moving[:, None], floor + after, velocities)
        m = np.where(moving, self._mass, 0.0)
        self._removed += float(0.5 * np.sum(m * (speed * speed - np.sum(after * after, axis=1))))
        if self._rotor is not None:
            self._supplied += float(np.sum(m * np.sum((after - relative) * floor, axis=1)))
        return new


@_register
class AirDrag(Kick):
    """Quadratic drag F = ½ ρ C_d A |v| v (still air), A = 2 r t: per granule dv/dt = −k|v|v,
    k = ½ρ C_d A/m, integrated exactly over the step (|v'| = |v|/(1 + k|v|dt), never reverses).
    Removes ½m(|v|² − |v'|²) per kick."""

    name = "air_drag"
    term = "drag"

    def __init__(self, scene: Scene, spec: AirDragSpec) -> None:
        super().__init__()
        self._k = np.array(
            [
                u.to_internal(
                    0.5
                    * spec.air_density
                    * spec.drag_coefficient
                    * 2
                    * g.radius
                    * spec.thickness
                    / g.mass,
                    1.0 / u.LENGTH,
                )
                for g in scene.spec.granules
            ],
            dtype=np.float64,
        )
        self._mass = _granule_masses(scene)

    def kick(self, velocities: FloatArray, positions: FloatArray | None, dt: float) -> FloatArray:
        speed = _speeds(velocities)
        moving = speed > 0.0
        after = speed / (1.0 + self._k * speed * dt)
        ratio = np.where(moving, after / np.where(moving, speed, 1.0), 1.0)
        m = np.where(moving, self._mass, 0.0)
        self._removed += float(0.5 * np.sum(m * (speed * speed - after * after)))
        return velocities * ratio[:, None]


def build_effects(scene: Scene) -> list[Effect]:
    """Build the effects ``scene.spec.effects`` lists, in registry order; if some are kicks on
    Pymunk granules, the first of them gets the runner (a
    :class:`~perga.contact.rigid.batch.GranuleWriter`) for all. Soft granules (``spec.soft``) are
    kicked by their simulation through :func:`run_kicks`."""
    listed = scene.spec.effects
    effects = [
        make(scene, getattr(listed, name))
        for name, make in _REGISTRY.items()
        if getattr(listed, name) is not None
    ]
    kicks = [e for e in effects if isinstance(e, Kick)]
    if kicks and scene.spec.soft is None:
        kicks[0]._runner = _Kicks(scene, kicks)
    return effects
