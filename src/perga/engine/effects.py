"""Optional physics, built with the machine (:func:`~perga.engine.machine.build_machine`) only
when the spec lists it (design §3): an absent effect leaves no per-step hook, constraint or
callback.

Each effect is a class registered under its :class:`~perga.model.spec.EffectsSpec` field name.
Effects that act on granule velocities (floor friction, air drag) are *kicks*: array operations
on all granules at once, with no per-granule Python. Once per machine step, **before** the
contact model moves anything (:meth:`~perga.engine.simulation.Simulation.step`), a
:class:`KickRunner` reads every granule's velocity (and position, for the co-rotating floor)
from the contact model in one pass, every listed kick changes the velocity arrays in registry
order, each a velocity change over dt that never reverses the velocity it opposes, and one
write sets them. Effects that are constraints (hinge friction, drive) are pymunk motors.

Where the kick sits (an operator split): kick (at x_n, v_n), then the contacts and Chipmunk's
step drift with the kicked velocity and apply their impulses. First order in dt; the kick sees
the position at the start of the step, and an impact's approach speed includes the step's
friction and drag (docs/validation.md has the measured effect on the closed forms).

Energy: every effect counts, in J, the energy it removed (``removed`` >= 0) and the work the
rotor did through it (``supplied``, only the co-rotating floor), each from its own kicks or
impulses, never from a global balance. The ledger (:mod:`perga.engine.energy`) sums them by
``term``. A kick's energy is the exact change it made, granule by granule, summed over the
granules in numpy.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Literal, NamedTuple

import numpy as np
import pymunk
from numpy.typing import NDArray

from perga.engine import units as u
from perga.model.spec import AirDragSpec, DriveSpec, FloorFrictionSpec

if TYPE_CHECKING:
    from perga.contact.protocol import GranuleKinematics
    from perga.engine.machine import Machine

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


class Kick(Effect):
    """An effect that changes all granules' velocities once per step, before the contacts and
    Chipmunk's step, as array operations (module docstring), run by a :class:`KickRunner`."""

    def __init__(self) -> None:
        super().__init__()
        self.needs_positions = False
        """Whether :meth:`kick` needs the granules' positions."""

    def kick(
        self, velocities: FloatArray, positions: FloatArray | None, granules: Granules, dt: float
    ) -> FloatArray:
        """The granules' velocities after one step of ``dt`` of this effect (internal units;
        ``positions`` given if :attr:`needs_positions`; ``granules`` their masses and radii,
        SI). Counts the energy and must not change its arguments."""
        raise NotImplementedError


class KickRunner:
    """Runs the kicks among ``effects`` on the granules of a contact model: one read, each kick
    in registry order, one write (internal units)."""

    def __init__(self, effects: list[Effect], granules: GranuleKinematics) -> None:
        self.kicks = [e for e in effects if isinstance(e, Kick)]
        self.granules = granules
        self._positions = any(k.needs_positions for k in self.kicks)

    def __bool__(self) -> bool:
        return bool(self.kicks)

    def run(self, dt: float) -> None:
        """Kick every granule over ``dt`` (internal time units)."""
        if self.granules.count == 0:
            return
        velocities, positions = self.granules.read_internal(positions=self._positions)
        granules = Granules(*self.granules.constants())
        for effect in self.kicks:
            velocities = effect.kick(velocities, positions, granules, dt)
        self.granules.write_internal_velocities(velocities)


class Granules(NamedTuple):
    """What a kick needs of the granules besides their motion: masses (kg), radii (m)."""

    masses: FloatArray
    radii: FloatArray


def _speeds(v: FloatArray) -> FloatArray:
    return np.sqrt(v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1])


_REGISTRY: dict[str, Callable[[Machine, Any], Effect]] = {}


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

    def __init__(self, machine: Machine, spec: DriveSpec) -> None:
        super().__init__()
        welded = [h for h in machine.spec.hammers if h.mount == "welded"]
        moment = spec.inertia + sum(
            h.moment_about_centre + h.mass * (h.centre_on_rotor[0] ** 2 + h.centre_on_rotor[1] ** 2)
            for h in welded
        )
        mass = 2 * spec.inertia / machine.spec.rotor.radius**2 + sum(h.mass for h in welded)
        rotor, static = machine.rotor, machine.space.static_body
        omega = rotor.angular_velocity
        rotor.body_type = pymunk.Body.DYNAMIC
        rotor.mass = u.to_internal(mass, u.MASS)
        rotor.moment = u.to_internal(moment, u.MOMENT)
        rotor.angular_velocity = omega
        self.pivot = pymunk.PivotJoint(rotor, static, (0.0, 0.0))
        self.motor = pymunk.SimpleMotor(rotor, static, omega)
        self.motor.max_force = u.to_internal(spec.torque_limit, TORQUE)
        machine.space.add(self.pivot, self.motor)


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

    def __init__(self, machine: Machine, torque: float) -> None:
        super().__init__()
        self.motors: list[pymunk.SimpleMotor] = []
        for joint in machine.hinges:
            motor = pymunk.SimpleMotor(joint.b, joint.a, 0.0)
            motor.max_force = u.to_internal(torque, TORQUE)
            motor.collide_bodies = False
            self._watch(motor)
            machine.space.add(motor)
            self.motors.append(motor)


class SwingStops(_AngularImpulseLosses):
    """The stops of hinged hammers (``RotaryLimitJoint``, built with the machine when a hammer has
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

    def __init__(self, machine: Machine, spec: FloorFrictionSpec) -> None:
        super().__init__()
        self._deceleration = u.to_internal(spec.friction * spec.gravity, u.ACCELERATION)
        self._rotor = machine.rotor if spec.floor == "corotating" else None
        self.needs_positions = self._rotor is not None

    def kick(
        self, velocities: FloatArray, positions: FloatArray | None, granules: Granules, dt: float
    ) -> FloatArray:
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
        m = np.where(moving, granules.masses / u.MASS, 0.0)
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

    def __init__(self, machine: Machine, spec: AirDragSpec) -> None:
        super().__init__()
        self._spec = spec

    def kick(
        self, velocities: FloatArray, positions: FloatArray | None, granules: Granules, dt: float
    ) -> FloatArray:
        s = self._spec
        k = (
            0.5
            * s.air_density
            * s.drag_coefficient
            * 2
            * granules.radii
            * s.thickness
            / granules.masses
        ) / (1.0 / u.LENGTH)
        speed = _speeds(velocities)
        moving = speed > 0.0
        after = speed / (1.0 + k * speed * dt)
        ratio = np.where(moving, after / np.where(moving, speed, 1.0), 1.0)
        m = np.where(moving, granules.masses / u.MASS, 0.0)
        self._removed += float(0.5 * np.sum(m * (speed * speed - after * after)))
        return velocities * ratio[:, None]


def build_effects(machine: Machine) -> list[Effect]:
    """Build the effects ``machine.spec.effects`` lists, in registry order."""
    listed = machine.spec.effects
    return [
        make(machine, getattr(listed, name))
        for name, make in _REGISTRY.items()
        if getattr(listed, name) is not None
    ]
