"""Optional physics, built by :func:`~perga.engine.scene.build_scene` only when the spec lists
it (design §3): an absent effect leaves no velocity function, constraint or callback.

Each effect is a class registered under its :class:`~perga.engine.spec.EffectsSpec` field name.
Effects that act on granule velocities (floor friction, air drag) are *kicks*: one shared
velocity function per granule runs Chipmunk's default integration (gravity) and then every
kick, each a velocity change over dt that never reverses the velocity it opposes. Effects that
are constraints (hinge friction, drive) are pymunk motors.

Energy: every effect counts, in J, the energy it removed (``removed`` >= 0) and the work the
rotor did through it (``supplied``, only the co-rotating floor), each from its own kicks or
impulses, never from a global balance. The ledger (:mod:`perga.engine.energy`) sums them by
``term``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import pymunk

from perga.engine import units as u
from perga.engine.spec import AirDragSpec, DriveSpec, FloorFrictionSpec

if TYPE_CHECKING:
    from perga.engine.scene import Scene

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit (1e-3)."""

Term = Literal["friction", "drag", "drive"]


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


class Kick(Effect):
    """An effect applied in the granules' velocity function after gravity."""

    def kick(self, body: pymunk.Body, dt: float) -> None:
        """Change ``body.velocity`` for one step of ``dt`` (internal units)."""
        raise NotImplementedError


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


@_register
class HingeFriction(Effect):
    """Coulomb friction torque at every hinge: per hinged hammer a ``SimpleMotor(hammer,
    rotor, 0)`` with ``max_force`` = the torque (Chipmunk's joint-friction idiom). Removed
    energy per step: |j|·|ω̄_rel|, the motor's angular impulse times the mean of the relative
    angular velocity before and after the step (exact for one impulse on a pair of bodies)."""

    name = "hinge_friction"
    term = "friction"

    def __init__(self, scene: Scene, torque: float) -> None:
        super().__init__()
        self.motors: list[pymunk.SimpleMotor] = []
        self._before: dict[pymunk.Constraint, float] = {}
        for joint in scene.joints:
            motor = pymunk.SimpleMotor(joint.b, joint.a, 0.0)
            motor.max_force = u.to_internal(torque, TORQUE)
            motor.collide_bodies = False
            motor.pre_solve = self._pre_solve
            motor.post_solve = self._post_solve
            scene.space.add(motor)
            self.motors.append(motor)

    @staticmethod
    def _relative(motor: pymunk.Constraint) -> float:
        return motor.a.angular_velocity - motor.b.angular_velocity

    def _pre_solve(self, motor: pymunk.Constraint, _space: pymunk.Space) -> None:
        self._before[motor] = self._relative(motor)

    def _post_solve(self, motor: pymunk.Constraint, _space: pymunk.Space) -> None:
        mean = 0.5 * (self._before[motor] + self._relative(motor))
        self._removed += motor.impulse * abs(mean)


@_register
class FloorFriction(Kick):
    """Coulomb floor friction under a horizontal rotor: a velocity change of at most μ g dt
    opposing the granule's velocity relative to the floor (ω × r for the co-rotating floor,
    ω the rotor's current angular velocity; zero for the stationary one), clamped so that the
    relative velocity stops rather than reverses.

    A kick from v to v' with floor velocity w removes ½m(|v − w|² − |v' − w|²) and the
    floor does work m(v' − v)·w (the rotor's share). On a driven rotor the floor's reaction
    torque is not applied to the rotor (a limitation)."""

    name = "floor_friction"
    term = "friction"

    def __init__(self, scene: Scene, spec: FloorFrictionSpec) -> None:
        super().__init__()
        self._deceleration = u.to_internal(spec.friction * spec.gravity, u.ACCELERATION)
        self._rotor = scene.rotor if spec.floor == "corotating" else None

    def kick(self, body: pymunk.Body, dt: float) -> None:
        v = body.velocity
        if self._rotor is None:
            floor = pymunk.Vec2d(0.0, 0.0)
        else:
            w, p = self._rotor.angular_velocity, body.position
            floor = pymunk.Vec2d(-w * p.y, w * p.x)
        relative = v - floor
        speed = relative.length
        if speed == 0.0:
            return
        after = relative * (1.0 - min(self._deceleration * dt, speed) / speed)
        body.velocity = floor + after
        m = body.mass
        self._removed += 0.5 * m * (speed * speed - after.dot(after))
        self._supplied += m * (after - relative).dot(floor)


@_register
class AirDrag(Kick):
    """Quadratic drag F = ½ ρ C_d A |v| v (still air), A = 2 r t: per granule dv/dt = −k|v|v,
    k = ½ρ C_d A/m, integrated exactly over the step (|v'| = |v|/(1 + k|v|dt), never reverses).
    Removes ½m(|v|² − |v'|²) per kick."""

    name = "air_drag"
    term = "drag"

    def __init__(self, scene: Scene, spec: AirDragSpec) -> None:
        super().__init__()
        self._k: dict[pymunk.Body, float] = {
            body: u.to_internal(
                0.5
                * spec.air_density
                * spec.drag_coefficient
                * 2
                * g.radius
                * spec.thickness
                / g.mass,
                1.0 / u.LENGTH,
            )
            for g, body in zip(scene.spec.granules, scene.granule_bodies, strict=True)
        }

    def kick(self, body: pymunk.Body, dt: float) -> None:
        v = body.velocity
        speed = v.length
        if speed == 0.0:
            return
        after = speed / (1.0 + self._k[body] * speed * dt)
        body.velocity = v * (after / speed)
        self._removed += 0.5 * body.mass * (speed * speed - after * after)


def _velocity_func(kicks: list[Kick]) -> Callable[[pymunk.Body, Any, float, float], None]:
    def update(body: pymunk.Body, gravity: Any, damping: float, dt: float) -> None:
        pymunk.Body.update_velocity(body, gravity, damping, dt)
        for effect in kicks:
            effect.kick(body, dt)

    return update


def build_effects(scene: Scene) -> list[Effect]:
    """Build the effects ``scene.spec.effects`` lists, in registry order, and give the granules
    a velocity function only if some effect is a kick."""
    listed = scene.spec.effects
    effects = [
        make(scene, getattr(listed, name))
        for name, make in _REGISTRY.items()
        if getattr(listed, name) is not None
    ]
    kicks = [e for e in effects if isinstance(e, Kick)]
    if kicks:
        update = _velocity_func(kicks)
        for body in scene.granule_bodies:
            body.velocity_func = update
    return effects
