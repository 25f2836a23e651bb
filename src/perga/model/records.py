"""What a simulation reports besides its state, SI units: impacts, hammer states and the energy
ledger. Plain frozen dataclasses, written by the contact models and the engine, read by the
recorders and the statistics."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

TINY = 1e-30
"""J: the floor of the energy in play (a scene where nothing moves has closure 0)."""


@dataclass(frozen=True)
class HammerState:
    """A hammer at one instant: kinetic energy ½Mv_c² + ½I_cΩ², J; swing angle α, rad; absolute
    angular velocity Ω, rad/s (welded hammers move with the rotor: their α is the spec's);
    its centre of mass in the fixed frame, m."""

    energy: float
    swing_angle: float
    angular_velocity: float
    centre: tuple[float, float]


@dataclass(frozen=True)
class Impact:
    """One granule-hammer impact, SI units.

    time: s, the end of the machine step in which the contact began; granule, hammer: indices in
    the spec; normal_velocity_before/after: the granule's velocity relative to the hammer's
    material point at the contact, along the hammer's outward normal n (m/s; < 0 approaching,
    > 0 separating); tangential_velocity_before/after: the same along t = n turned +90° (m/s);
    normal_impulse: impulse on the granule along n, N·s (>= 0); point: contact point, m;
    normal: n; granule_energy_gain: change of the granule's kinetic energy (translation and
    spin) over the impact, J; dissipated: energy lost in this contact, J;
    hammer_energy_before: the hammer's kinetic energy ½Mv_c² + ½I_cΩ² at the impact's start, J;
    granule_velocity_before: the granule's velocity in the fixed frame before the impact, m/s;
    hammer_swing_angle_before, hammer_angular_velocity_before: the hammer's α (rad) and absolute
    angular velocity Ω (rad/s) at the impact's start; granule is the granule's id. Each contact
    model says what "before" and "after" are for its contacts (:mod:`perga.contact.rigid.impacts`,
    :mod:`perga.contact.soft.impacts`).
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
    specific_energy: float = math.nan
    """W = ½v_n² of the approach, J/kg (from ``normal_velocity_before`` unless given)."""
    breakage_probability: float = math.nan
    """The chance this impact broke the granule, 1 − exp(−f_mat·x·(W − W_min)⁺), with damage."""
    survival: float = math.nan
    """The granule's expected survival after this impact, with damage."""
    peak_force: float = math.nan
    """The largest normal contact force during the impact, N (soft contacts)."""
    peak_pressure: float = math.nan
    """Hertz's peak contact pressure at ``peak_force``, p0 = (2E*/π)·√(δ/R), Pa (soft Hertz
    contacts; a diagnostic of damage)."""
    granule_spin_before: float = math.nan
    """The granule's angular velocity at the impact's start, rad/s (0 for a sliding point)."""
    granule_spin_after: float = math.nan
    """The granule's angular velocity at the impact's end, rad/s."""
    hammer_centre_before: tuple[float, float] = (math.nan, math.nan)
    """The hammer's centre of mass at the impact's start, fixed frame, m."""
    granule_velocity_after: tuple[float, float] = (math.nan, math.nan)
    """The granule's velocity in the fixed frame at the impact's end, m/s."""
    held: bool = False
    """The granule was held in its cell (a comb's) at the impact's start."""
    other_contacts: int = -1
    """Contacts on the granule, or on the hammer if it is not carried by a rotor of prescribed
    motion, besides this impact's (rigid: in its step; soft: the more of those at its start and
    at its end); 0: the impact is isolated; -1: not recorded."""

    def __post_init__(self) -> None:
        if math.isnan(self.specific_energy):
            object.__setattr__(self, "specific_energy", 0.5 * self.normal_velocity_before**2)


@dataclass(frozen=True)
class Contact:
    """One granule-hammer contact from its start to its end, SI units: what a slide along a
    hammer face is compared with (:mod:`perga.stats.slide_law`).

    granule, hammer: ids; start, end: s, the times of the first and last states; steps: the
    machine steps the contact lasted; normal: the hammer's outward normal at the start;
    position_start, velocity_start (m, m/s, fixed frame), spin_start (rad/s): the granule at
    the start; the same at the end; hammer_turn: the angle the hammer turned through from
    start to end, rad; hammer_angular_velocity_start/end: its absolute angular velocity,
    rad/s; other_contacts: the most contacts the
    granule had besides this one at once (rigid: in any of its steps; soft: at its start and
    end; a hammer's other pieces belong to this contact); held: the granule was held in its
    cell at the start; touches: the contacts with other granules and the wall the granule had
    begun before this one's first state (−1: not counted), so that no such contact began
    between two of its contacts when both have the same count. Each contact model says what
    its start and end states are
    (:mod:`perga.contact.rigid.impacts`, :mod:`perga.contact.soft.impacts`).
    """

    granule: int
    hammer: int
    start: float
    end: float
    steps: int
    normal: tuple[float, float]
    position_start: tuple[float, float]
    velocity_start: tuple[float, float]
    spin_start: float
    position_end: tuple[float, float]
    velocity_end: tuple[float, float]
    spin_end: float
    hammer_turn: float
    hammer_angular_velocity_start: float
    hammer_angular_velocity_end: float
    other_contacts: int
    held: bool
    touches: int = -1


@dataclass(frozen=True)
class Release:
    """A granule pulled out of its comb cell: at ``time`` (s, the end of the machine step),
    granule ``granule`` (its id), by a bond reaction of ``force`` (N) above its threshold."""

    time: float
    granule: int
    force: float


@dataclass(frozen=True)
class Departure:
    """A granule that left through the outlet at ``time`` (s): its id, radius (m), mass (kg),
    speed (m/s), impacts with hammers (-), expected survival (-, 1 without damage), whether
    it broke (drawn), and its time in the chamber since it was fed or released (s)."""

    time: float
    granule: int
    radius: float
    mass: float
    speed: float
    impacts: int
    survival: float
    broken: bool
    residence_time: float


@dataclass(frozen=True)
class Events:
    """Everything a run has recorded so far, in order: granule-hammer impacts, granules released
    from their cells, granules gone through the outlet, granule-hammer contacts ended."""

    impacts: Sequence[Impact] = ()
    releases: Sequence[Release] = ()
    departures: Sequence[Departure] = ()
    contacts: Sequence[Contact] = ()


@dataclass(frozen=True)
class EnergyLedger:
    """Cumulative energy terms since t = 0, J (SI); ``closure`` is dimensionless.

    The terms, the residual, the energy in play and the closure are defined in
    :mod:`perga.machine.energy`."""

    kinetic: float
    """Current kinetic energy of all moving bodies and granules (translation and rotation)."""
    kinetic_initial: float
    """Kinetic energy at t = 0."""
    drive_work: float
    """Work done by the rotor (kinematic or driven) on the other bodies."""
    gravity_work: float
    """Work done by in-plane gravity (potential energy released)."""
    contact_dissipation: float
    """Energy lost in granule-hammer, granule-granule and granule-wall contacts."""
    friction: float
    """Energy removed by floor and hinge friction."""
    drag: float
    """Energy removed by air drag."""
    residual: float
    """drive + gravity + joint correction + inflow − outflow − ΔKE − Δelastic − contact −
    friction − drag: what the ledger misses."""
    energy_in_play: float
    """The energy the residual is judged against: the largest of the work done, the energy
    moved between bodies and the granules' energy now and at the start."""
    closure: float
    """residual / energy_in_play."""
    elastic: float = 0.0
    """Energy stored in soft contacts now (0 with rigid contacts)."""
    elastic_initial: float = 0.0
    """Energy stored in soft contacts at t = 0."""
    inflow: float = 0.0
    """Energy brought in by granules fed into the chamber (their kinetic energy)."""
    outflow: float = 0.0
    """Energy taken out by granules removed (kinetic and stored elastic energy)."""
    joint_correction: float = 0.0
    """Work the hinge pins' position correction did (numerical: an ideal pin does none; first
    order in dt)."""


@dataclass(frozen=True)
class LedgerTerms:
    """The measured terms of a ledger before closing it (J), as one part of a simulation measures
    them (the machine's meter, a contact model): see :class:`EnergyLedger`; ``moved`` is
    ½Σ_i|ΔKE_i|, the kinetic energy moved between bodies. Parts add up with ``+``."""

    kinetic: float = 0.0
    kinetic_initial: float = 0.0
    moved: float = 0.0
    drive_work: float = 0.0
    gravity_work: float = 0.0
    contact_dissipation: float = 0.0
    friction: float = 0.0
    drag: float = 0.0
    elastic: float = 0.0
    elastic_initial: float = 0.0
    inflow: float = 0.0
    outflow: float = 0.0
    joint_correction: float = 0.0

    def __add__(self, other: LedgerTerms) -> LedgerTerms:
        return LedgerTerms(
            **{f.name: getattr(self, f.name) + getattr(other, f.name) for f in fields(self)}
        )

    def close(self, granules: LedgerTerms) -> EnergyLedger:
        """The ledger with its closure: the residual over the energy in play, the largest of
        |drive_work|, |ΔKE + Δelastic|, |gravity_work|, ``moved``, inflow, outflow, the
        granules' kinetic and elastic energy now and at the start (``granules``: their own
        terms, a part of these) and :data:`TINY`. The machine's own kinetic energy is left out:
        a hammer carried round at constant speed holds energy that nothing exchanges."""
        change = self.kinetic - self.kinetic_initial + self.elastic - self.elastic_initial
        residual = (
            self.drive_work
            + self.gravity_work
            + self.joint_correction
            + self.inflow
            - self.outflow
            - change
            - self.contact_dissipation
            - self.friction
            - self.drag
        )
        in_play = max(
            abs(self.drive_work),
            abs(change),
            abs(self.gravity_work),
            self.moved,
            self.inflow,
            self.outflow,
            granules.kinetic + granules.elastic,
            granules.kinetic_initial + granules.elastic_initial,
            TINY,
        )
        return EnergyLedger(
            kinetic=self.kinetic,
            kinetic_initial=self.kinetic_initial,
            drive_work=self.drive_work,
            gravity_work=self.gravity_work,
            contact_dissipation=self.contact_dissipation,
            friction=self.friction,
            drag=self.drag,
            residual=residual,
            energy_in_play=in_play,
            closure=residual / in_play,
            elastic=self.elastic,
            elastic_initial=self.elastic_initial,
            inflow=self.inflow,
            outflow=self.outflow,
            joint_correction=self.joint_correction,
        )
