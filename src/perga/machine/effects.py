"""Optional physics, built with the machine (:func:`~perga.machine.machine.build_machine`) only
when the spec lists it: an absent effect leaves no per-step hook, constraint or
callback.

Each effect is a class registered under its :class:`~perga.model.system.EffectsSpec` field name.
Effects that act on granule velocities (floor friction, air drag) are *kicks*: one compiled
loop over all granules (numba), with no per-granule Python. Once per machine step, **before**
the contact model moves anything (:meth:`~perga.engine.simulation.Simulation.step`), a
:class:`KickRunner` takes every granule's velocity (and position, for the co-rotating floor)
from the contact model (the soft kernel's own arrays, or one batch read of the rigid bodies),
every listed kick changes the velocity array in place in registry order, each a velocity
change over dt that never reverses the velocity it opposes, and one write sets them (none for
the kernel's arrays). A contact model may take the last kick over and apply it itself, after
the others and before it moves anything: the soft kernel applies floor friction
(:class:`FloorKick`) at the start of its call, the same compiled loop on the same arrays. The
kicks and their laws are in SI (m, s, kg, J), whatever a contact model keeps its granules in.
Effects that are constraints (hinge friction, drive) are pymunk motors, and book their losses
in Chipmunk's internal units (:mod:`perga.machine.units`).

Where the kick sits (an operator split): kick (at x_n, v_n), then the contacts and Chipmunk's
step drift with the kicked velocity and apply their impulses. First order in dt; the kick sees
the position at the start of the step, and an impact's approach speed includes the step's
friction and drag (docs/dev/validation.md has the measured effect on the closed forms).

Energy: every effect counts, in J, the energy it removed (``removed`` >= 0) and the work the
rotor did through it (``supplied``, only the co-rotating floor), each from its own kicks or
impulses, never from a global balance. The ledger (:mod:`perga.machine.energy`) sums them by
``term``. A kick's energy is the exact change it made, granule by granule, summed in the loop
that makes it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Literal, NamedTuple, Protocol

import numba
import numpy as np
import pymunk
from numpy.typing import NDArray

from perga.machine import units as u
from perga.machine.chipmunk_state import JointImpulses, doubles_at
from perga.model.system import AirDragSpec, DriveSpec, FloorFrictionSpec

if TYPE_CHECKING:
    from perga.machine.machine import Machine

TORQUE = u.FORCE * u.LENGTH
"""N·m per internal torque unit (1e-3)."""

Term = Literal["friction", "drag", "drive", "contact"]
FloatArray = NDArray[np.float64]


class GranuleKinematics(Protocol):
    """All granules' velocities, read and written at once for the effects' kicks, rows in the
    spec's granule order, SI."""

    @property
    def count(self) -> int:
        """Number of granules."""
        ...

    def constants(self) -> tuple[FloatArray, FloatArray]:
        """The granules' masses (kg) and radii (m), rows as the velocities' (read only: they
        may be the model's own arrays)."""
        ...

    def read(self, *, positions: bool) -> tuple[FloatArray, FloatArray | None]:
        """Velocities (n, 2), m/s, and positions (n, 2), m, if asked for (else None): the
        model's own arrays or fresh ones."""
        ...

    def write_velocities(self, velocities: FloatArray) -> None:
        """Set every granule's velocity from ``velocities`` (n, 2), as :meth:`read` gave them."""
        ...

    def take_floor_kick(self, kick: FloorKick) -> bool:
        """Whether the model takes floor friction's kick over: it then applies ``kick`` at the
        start of its work before the machine's step
        (:meth:`~perga.contact.protocol.ContactModel.before_machine_step`), with the rotor's
        angular velocity of the state it is given, instead of the effects' runner before it."""
        ...


class Effect:
    """Base of all effects: the ledger term its removed energy belongs to, and its counters
    (kept in ``energy_unit``, read in J)."""

    name: ClassVar[str]
    term: ClassVar[Term]
    energy_unit: ClassVar[float] = u.ENERGY
    """J per unit of the counters: Chipmunk's internal energy unit (constraints, whose losses
    are booked from the machine's states in internal units)."""

    def __init__(self) -> None:
        self._energy = np.zeros(2)
        """Removed and supplied so far, in ``energy_unit``: an array, so that a contact model
        applying this effect's kick in its own compiled step can add to it (:class:`FloorKick`)."""

    @property
    def removed(self) -> float:
        """Energy this effect has taken out of the bodies since t = 0, J (>= 0)."""
        return float(self._energy[0]) * self.energy_unit

    @property
    def supplied(self) -> float:
        """Work the rotor has done on the bodies through this effect since t = 0, J."""
        return float(self._energy[1]) * self.energy_unit


class Kick(Effect):
    """An effect that changes all granules' velocities once per step, before the contacts and
    Chipmunk's step, as array operations (module docstring), run by a :class:`KickRunner`; its
    counters are in J."""

    energy_unit = 1.0

    def __init__(self) -> None:
        super().__init__()
        self.needs_positions = False
        """Whether :meth:`kick` needs the granules' positions."""

    def kick(self, granules: Granules, dt: float) -> None:
        """Change the ``granules``' velocities in place by one step of ``dt`` (s) of this effect
        and count the energy (J); their positions are given if :attr:`needs_positions`."""
        raise NotImplementedError

    def hand_over(self, granules: GranuleKinematics, dt: float) -> bool:
        """Whether the contact model of ``granules`` takes this kick over, to apply it itself
        at the start of each machine step of ``dt`` (s); none does but :class:`FloorFriction`'s."""
        return False


class KickRunner:
    """Runs the kicks among ``effects`` on the granules of a contact model: one read, each kick
    in registry order, one write (SI). The last kick, if the contact model takes it over
    (:meth:`Kick.hand_over`; machine steps of ``dt``, s), is the model's to apply after the
    others, at the start of its own work in the step, and not run here."""

    def __init__(self, effects: list[Effect], granules: GranuleKinematics, dt: float) -> None:
        self.kicks = [e for e in effects if isinstance(e, Kick)]
        if self.kicks and self.kicks[-1].hand_over(granules, dt):
            self.kicks.pop()
        self.granules = granules
        self._positions = any(k.needs_positions for k in self.kicks)

    def __bool__(self) -> bool:
        return bool(self.kicks)

    def run(self, dt: float) -> None:
        """Kick every granule over ``dt`` (s)."""
        if self.granules.count == 0:
            return
        velocities, positions = self.granules.read(positions=self._positions)
        granules = Granules(
            np.ascontiguousarray(velocities),  # the kernel's own array; a rigid read's copy
            None if positions is None else np.ascontiguousarray(positions),
            *self.granules.constants(),
        )
        for effect in self.kicks:
            effect.kick(granules, dt)
        self.granules.write_velocities(granules.velocities)


class FloorKick(NamedTuple):
    """:class:`FloorFriction`'s kick as a contact model applies it (:meth:`Kick.hand_over`): at
    the start of each machine step, ``floor_kick`` on its granules with ``dv_max`` (m/s) and
    the rotor's angular velocity at the step's start (rad/s) if ``corotating`` (else 0, the
    granules' velocities standing for their positions, as :class:`KickRunner` gives them),
    which adds the energy it removed and the floor's work to ``energy`` (the effect's counters,
    J, in place)."""

    dv_max: float
    corotating: bool
    energy: FloatArray


class Granules(NamedTuple):
    """The granules a kick changes: velocities (n, 2), m/s, and positions (n, 2), m, or None,
    C-contiguous (:class:`GranuleKinematics`), masses (kg), radii (m)."""

    velocities: FloatArray
    positions: FloatArray | None
    masses: FloatArray
    radii: FloatArray


_REGISTRY: dict[str, Callable[[Machine, Any], Effect]] = {}


def _register(cls: type[Effect]) -> type[Effect]:
    _REGISTRY[cls.name] = cls
    return cls


@_register
class Drive(Effect):
    """The rotor becomes a dynamic body of the spec's inertia (plus the welded hammers' moments
    about the axis), pinned to the static body at the axis and driven by
    ``SimpleMotor(rotor, static_body, ω)`` (this order turns it forward, docs/pymunk.md) whose
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


class ConstraintLosses(Effect):
    """An effect whose constraints act on the relative rotation of two bodies, removing per step
    −j·ω̄_rel: the constraint's signed angular impulse on b in the step times the mean of the
    relative angular velocity ω_b − ω_a before and after the step (exact for one impulse on a
    pair of bodies).

    No Chipmunk callback: the energy meter hands the machine's states before and after the step
    to :func:`constraint_losses` (:mod:`perga.machine.energy`), which equal what a constraint's
    ``pre_solve`` and ``post_solve`` see (Chipmunk integrates positions, then calls
    ``pre_solve`` before touching velocities, and ``post_solve`` after the last iteration);
    ``constraint.impulse`` read after the step is the step's impulse ``post_solve`` reads.
    """

    def __init__(self, machine: Machine) -> None:
        super().__init__()
        self._machine = machine
        self._watched: list[tuple[pymunk.Constraint, int, int]] = []
        self._impulses: JointImpulses | None = None
        self._rows = np.zeros((0, 2), dtype=np.int64)
        """Each watched constraint's bodies' rows in a :class:`MachineState` (a, b)."""

    def _watch(self, constraint: pymunk.Constraint) -> None:
        m = self._machine
        self._watched.append((constraint, m.row_of(constraint.a), m.row_of(constraint.b)))

    def losses(self) -> tuple[FloatArray, NDArray[np.uint64], np.ndarray]:
        """The arguments of :func:`constraint_losses` but the states: the removed and supplied
        energy (internal units, added to in place), the watched constraints' jAcc addresses
        (read raw: pymunk gives only |j|) and their bodies' rows in a :class:`MachineState`
        (made again when a constraint is watched, and after a checkpoint is read back)."""
        if self._impulses is None or len(self._impulses.joints) != len(self._watched):
            self._impulses = JointImpulses([c for c, _, _ in self._watched])
            rows = [(a, b) for _, a, b in self._watched]
            self._rows = np.array(rows, dtype=np.int64).reshape(-1, 2)
        return self._energy, self._impulses.addresses(), self._rows


@_register
class HingeFriction(ConstraintLosses):
    """Coulomb friction torque at every hinge: per hinged hammer a ``SimpleMotor(hammer,
    rotor, 0)`` with ``max_force`` = the torque (Chipmunk's joint-friction idiom); its losses
    as :class:`ConstraintLosses`."""

    name = "hinge_friction"
    term = "friction"

    def __init__(self, machine: Machine, torque: float) -> None:
        super().__init__(machine)
        self.motors: list[pymunk.SimpleMotor] = []
        for joint in machine.hinges:
            motor = pymunk.SimpleMotor(joint.b, joint.a, 0.0)
            motor.max_force = u.to_internal(torque, TORQUE)
            motor.collide_bodies = False
            self._watch(motor)
            machine.space.add(motor)
            self.motors.append(motor)


class SwingStops(ConstraintLosses):
    """The stops of hinged hammers (``RotaryLimitJoint``, built with the machine when a hammer has
    a ``swing_limit``): a hammer swinging into its stop is stopped by a perfectly inelastic
    angular impulse, whose losses (:class:`ConstraintLosses`) count with the contacts'
    dissipation. Not in the registry: built for the hammers that have stops, not from
    ``EffectsSpec``."""

    name = "swing_stops"
    term = "contact"

    def __init__(self, machine: Machine, stops: list[pymunk.RotaryLimitJoint]) -> None:
        super().__init__(machine)
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
        self._deceleration = spec.friction * spec.gravity
        """μ g, m/s²."""
        self._rotor = machine.rotor if spec.floor == "corotating" else None
        self.needs_positions = self._rotor is not None

    def kick(self, granules: Granules, dt: float) -> None:
        g = granules
        omega = 0.0 if self._rotor is None else self._rotor.angular_velocity * u.ANGULAR_VELOCITY
        where = g.velocities if g.positions is None else g.positions  # unused without a rotor
        floor_kick(g.velocities, where, g.masses, self._deceleration * dt, omega, self._energy)

    def hand_over(self, granules: GranuleKinematics, dt: float) -> bool:
        kick = FloorKick(self._deceleration * dt, self._rotor is not None, self._energy)
        return granules.take_floor_kick(kick)


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

    def kick(self, granules: Granules, dt: float) -> None:
        s = self._spec
        k = 0.5 * s.air_density * s.drag_coefficient * 2 * granules.radii * s.thickness
        _drag_kick(granules.velocities, k / granules.masses * dt, granules.masses, self._energy)


@numba.njit(cache=True, fastmath=False)
def constraint_losses(
    energy: FloatArray,
    impulses: NDArray[np.uint64],
    rows: np.ndarray,
    before: np.ndarray,
    after: np.ndarray,
) -> None:
    """Take j·ω̄_rel from the removed energy ``energy[0]`` for each constraint in turn
    (:class:`ConstraintLosses`, whose :meth:`~ConstraintLosses.losses` gives the arguments
    but the machine-state tables): angular impulse j (its jAcc, the double at the address
    ``impulses[c]``, :meth:`~perga.machine.chipmunk_state.JointImpulses.addresses`) on body
    ``rows[c, 1]`` against ``rows[c, 0]``, ω̄_rel the mean of their relative angular velocity
    at the step's start and end (column 5 of the machine-state tables ``before`` and
    ``after``)."""
    removed = energy[0]
    for c in range(rows.shape[0]):
        a = rows[c, 0]
        b = rows[c, 1]
        rel = (before[b, 5] - before[a, 5]) + (after[b, 5] - after[a, 5])
        removed -= doubles_at(impulses[c], 1)[0] * (0.5 * rel)
    energy[0] = removed


@numba.njit(cache=True, fastmath=False)
def floor_kick(
    v: FloatArray,
    x: FloatArray,
    m: FloatArray,
    dv_max: float,
    omega: float,
    energy: FloatArray,
) -> None:
    """Floor friction on every granule in place (:class:`FloorFriction`), SI: the velocity
    ``v`` (n, 2), m/s, relative to the floor (ω × x for granules at ``x`` (n, 2), m; ω = 0,
    rad/s, for a stationary floor) loses at most ``dv_max`` (m/s) of its length; the energy
    removed and the floor's work, Σ over granules (masses ``m``, kg), are added to ``energy``
    (2,), J. ``v`` and ``x`` C-contiguous."""
    removed, supplied = _floor_kicks(v, x, m, dv_max, omega)
    energy[0] += removed
    energy[1] += supplied


@numba.njit(fastmath=False, inline="always")
def _floor_kicks(v, x, m, dv_max, omega):
    """:func:`floor_kick` (its arguments but energy; returns the two sums) in two loops: the
    kicks, over flat views and with selects for the granules at rest relative to the floor,
    which the compiler vectorises (IEEE division and square root are exact per lane: the same
    floats as one granule at a time), then the sums in granule order, to which a granule at
    rest adds −0.0 (x + (−0.0) is x for every x)."""
    n = v.shape[0]
    vf = v.reshape(-1)
    xf = x.reshape(-1)
    removed_each = np.empty(n)
    supplied_each = np.empty(n)
    for i in range(n):
        fx = -omega * xf[2 * i + 1]
        fy = omega * xf[2 * i]
        rx = vf[2 * i] - fx
        ry = vf[2 * i + 1] - fy
        speed = math.sqrt(rx * rx + ry * ry)
        moving = speed > 0.0
        scale = 1.0 - min(dv_max, speed) / (speed if moving else 1.0)
        ax = rx * scale
        ay = ry * scale
        vf[2 * i] = fx + ax if moving else vf[2 * i]
        vf[2 * i + 1] = fy + ay if moving else vf[2 * i + 1]
        removed = 0.5 * m[i] * (speed * speed - (ax * ax + ay * ay))
        supplied = m[i] * ((ax - rx) * fx + (ay - ry) * fy)
        removed_each[i] = removed if moving else -0.0
        supplied_each[i] = supplied if moving else -0.0
    removed = 0.0
    supplied = 0.0
    for i in range(n):
        removed += removed_each[i]
        supplied += supplied_each[i]
    return removed, supplied


@numba.njit(cache=True, fastmath=False)
def _drag_kick(v: FloatArray, k_dt: FloatArray, m: FloatArray, energy: FloatArray) -> None:
    """Quadratic drag on every granule in place (:class:`AirDrag`), SI: |v'| = |v|/(1 + k|v|dt)
    for the velocities ``v`` (n, 2), m/s, ``k_dt`` = k·dt per granule, 1/(m/s); adds the energy
    removed to ``energy[0]``, J (masses ``m``, kg)."""
    removed = 0.0
    for i in range(v.shape[0]):
        vx = v[i, 0]
        vy = v[i, 1]
        speed = math.sqrt(vx * vx + vy * vy)
        if speed > 0.0:
            after = speed / (1.0 + k_dt[i] * speed)
            ratio = after / speed
            v[i, 0] = vx * ratio
            v[i, 1] = vy * ratio
            removed += 0.5 * m[i] * (speed * speed - after * after)
    energy[0] += removed


def build_effects(machine: Machine) -> list[Effect]:
    """Build the effects ``machine.spec.effects`` lists, in registry order."""
    listed = machine.spec.effects
    return [
        make(machine, getattr(listed, name))
        for name, make in _REGISTRY.items()
        if getattr(listed, name) is not None
    ]
