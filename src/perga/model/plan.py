"""The time steps of a case: contact resolution, tunnelling and rotor-turn bounds, resolved.

Rigid contacts (Pymunk impulses) have no duration: the step is bounded by tunnelling (a granule
must not cross half a hammer or the wall in one step) and by the rotor's turn per step. Soft
contacts (``contact_model.kind`` a contact law, :mod:`perga.contact.laws`) also need the
shortest contact resolved by ``steps_per_contact`` steps (default 50, MercuryDPM convention);
their granules take ``granule_substeps`` steps per Pymunk step of the rotor and hammers. The
normal stiffness of the soft contacts is resolved here too, since the contact durations follow
from it; the law turns stiffness, damping and durations into one another.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from perga.analytic.common import reduced_mass
from perga.analytic.contact import mindlin_ratio, tunnelling_time_step
from perga.analytic.impact import free_effective_mass, hinged_effective_mass
from perga.case.schema import Case, ExplicitPlacement, ShotPlacement
from perga.model.hammer_geometry import hammer_geometry
from perga.model.parts import chamber_geometry
from perga.model.sizes import masses, radius_range

MAX_ROTATION_PER_STEP = 0.05
"""Largest rotor turn in one (Pymunk) step, rad (about 3°): hinge and contact geometry stay
resolved."""


def fastest_relative_speed(case: Case) -> float:
    """Upper bound on a granule's speed relative to a hammer or the wall, m/s: the hammer tip's
    speed on the rotor, plus a free hammer's speed, plus the fastest initial granule speed,
    plus with gravity in the plane the speed of a fall across the chamber, √(2g·2R) (R: the
    wall's farthest point from the axis)."""
    h = case.hammers
    tip = h.hinge_radius + hammer_geometry(case).tip
    speed = case.rotor.angular_velocity * tip + math.hypot(*h.velocity)
    placement = case.granules.placement
    if isinstance(placement, ExplicitPlacement) and placement.velocities:
        speed += float(np.max(np.hypot(*np.array(placement.velocities, dtype=float).T)))
    if isinstance(placement, ShotPlacement):
        speed += placement.speed
    wall = chamber_geometry(case)
    if case.effects.gravity_in_plane is not None and wall is not None:
        speed += math.sqrt(4.0 * case.gravity * wall.outer_radius)
    return speed


def thinnest_obstacle(case: Case) -> float:
    """The thinner of a hammer (its out-of-plane thickness) and the chamber wall, m."""
    hammer = hammer_geometry(case).thickness
    return min(hammer, case.chamber.wall_thickness) if case.chamber else hammer


def hammer_effective_mass(case: Case) -> float:
    """Smallest effective mass a hammer offers a granule's impact, kg: I_A/tip² for a hinged
    hammer struck at its tip (:func:`~perga.analytic.impact.hinged_effective_mass`), the free
    one's struck at its farthest point from the centre of mass
    (:func:`~perga.analytic.impact.free_effective_mass`), and infinite for a welded one (the
    rotor's inertia)."""
    h, g = case.hammers, hammer_geometry(case)
    if h.mount == "hinged":
        return hinged_effective_mass(g.moment_about_hinge, g.tip)
    if h.mount == "free":
        cx, cy = g.centre_of_mass
        arm = max(math.hypot(x - cx, y - cy) for x, y in g.outline)
        return free_effective_mass(g.mass, g.moment_about_hinge - g.mass * (cx * cx + cy * cy), arm)
    return math.inf


def _pairs(case: Case) -> list[tuple[str, float, float]]:
    """(name, reduced mass kg, effective radius m) of each soft contact kind the scene has, for
    its smallest granule (the shortest contacts)."""
    r = radius_range(case)[0]
    m = float(masses(case, np.array([r]))[0]) if case.granules.size else case.granule_mass
    hammer = hammer_effective_mass(case)
    pairs = [("granule-hammer", reduced_mass(m, hammer), r)]
    if case.chamber is not None:
        pairs.append(("granule-wall", m, r))
    if case.effects.granule_collisions is not None:
        pairs.append(("granule-granule", 0.5 * m, 0.5 * r))
    return pairs


def pair_materials(case: Case, name: str) -> tuple[str, str]:
    """The materials of a soft contact kind of :func:`_pairs` (granule-hammer, -wall,
    -granule)."""
    other = {
        "granule-hammer": case.hammers.material,
        "granule-wall": case.chamber.material if case.chamber else "",
        "granule-granule": case.granules.material,
    }[name]
    return case.granules.material, other


def normal_stiffness(case: Case) -> float:
    """The k_n every pair shares: contact_model.stiffness (N/m linear, Pa Hertz), or from
    contact_model.duration the k_n that makes a granule (of ``granules.radius`` and its mass)
    striking a rigid wall head-on with the granule-hammer restitution last that long: N/m
    (linear), or (4/3)E*, Pa (Hertz, at the fastest relative speed, where its contacts are
    shortest; t_c ∝ (k_n√r)^{-2/5} at a given α)."""
    cm = case.contact_model
    if cm.stiffness is not None:
        return cm.stiffness
    if cm.duration is None:
        raise ValueError("contact_model: no stiffness or duration shared by every pair")
    return stiffness_for_duration(case, cm.duration, case.granule_hammer_contact.restitution)


def stiffness_for_duration(case: Case, duration: float, e: float) -> float:
    """The k_n with which a granule (of ``granules.radius`` and its mass) striking a rigid wall
    head-on with restitution ``e`` stays ``duration`` (s) in contact: N/m (linear), or
    (4/3)E*, Pa (Hertz, at the fastest relative speed); the law's
    :meth:`~perga.contact.laws.base.ContactLaw.stiffness_for_duration`."""
    cm = case.contact_model
    v = max(fastest_relative_speed(case), 1e-3)
    return cm.law.stiffness_for_duration(
        duration, e, case.granule_mass, case.granules.radius, v, cm.end
    )


def _from_materials(case: Case, a: str, b: str) -> bool:
    """Whether the stiffness of the soft contacts between materials ``a`` and ``b`` comes from
    their Young's moduli and Poisson's ratios: a law that takes it from them, and no stiffness
    or duration given, shared or the pair's own."""
    cm, pair = case.contact_model, case.contact(a, b)
    return (
        cm.law.from_materials
        and cm.stiffness is None
        and cm.duration is None
        and pair.stiffness is None
        and pair.duration is None
    )


def _moduli(case: Case, a: str, b: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """((E_a, E_b), (ν_a, ν_b)) of materials ``a`` and ``b``, Pa and -; ValueError if any is
    not given."""
    m_a, m_b = case.materials[a], case.materials[b]
    E, nu = (m_a.youngs_modulus, m_b.youngs_modulus), (m_a.poisson_ratio, m_b.poisson_ratio)
    if None in (*E, *nu):
        raise ValueError(
            f"the {a}-{b} contact needs both materials' youngs_modulus and poisson_ratio"
        )
    return E, nu  # type: ignore[return-value]


def pair_stiffness(case: Case, a: str, b: str) -> float:
    """k_n of the soft contacts between materials ``a`` and ``b``: N/m (linear) or (4/3)E*, Pa
    (Hertz): the pair's own (its [[contacts]] stiffness, or duration by
    :func:`stiffness_for_duration` with its restitution), else contact_model's
    (:func:`normal_stiffness`), else (Hertz) from the materials' Young's moduli and Poisson's
    ratios (the law's ``stiffness_from_materials``, (4/3)E*); a Hertz contact's stiffness is
    this times √R*, R* = r_a r_b/(r_a + r_b) (r at a wall or hammer)."""
    pair = case.contact(a, b)
    if pair.stiffness is not None:
        return pair.stiffness
    if pair.duration is not None:
        return stiffness_for_duration(case, pair.duration, pair.restitution)
    if _from_materials(case, a, b):
        return case.contact_model.law.stiffness_from_materials(*_moduli(case, a, b))
    return normal_stiffness(case)


def tangential_ratio(case: Case, a: str, b: str) -> float:
    """k_t/k_n of the soft contacts between materials ``a`` and ``b``: contact_model's number;
    'mindlin', or by default for a pair of a law Mindlin's applies to (Hertz) whose stiffness
    comes from its materials, Mindlin's 6G*/E* (:func:`~perga.analytic.contact.mindlin_ratio`);
    else the law's default (2/7, as LAMMPS)."""
    cm = case.contact_model
    if isinstance(cm.tangential_ratio, float):
        return cm.tangential_ratio
    law = cm.law
    if cm.tangential_ratio == "mindlin" or (law.mindlin and _from_materials(case, a, b)):
        return mindlin_ratio(*_moduli(case, a, b))
    return law.default_tangential_ratio


TANGENTIAL_INERTIA = 3.0
"""A sticking disc contact's tangential over normal inverse mass: 1/m + r²/I = 3/m for a disc
(I = m r²/2) on a wall, 6/m = 3/m_eff for two equal discs (on a hammer 3/m_eff counts the
hammer's side thrice: a shorter period, a safe step)."""


def tangential_half_periods(case: Case) -> dict[str, float]:
    """Half-period π/ω_t of the tangential oscillation of a sticking contact of each soft contact
    kind (:func:`_pairs`, its smallest granule), s: ω_t² = TANGENTIAL_INERTIA·k_t/m_eff with
    k_t = ratio·k_n (linear), or ratio·k_n√(R*δ_max) (Hertz, at the largest overlap of an
    elastic head-on impact at the fastest relative speed, ½m_eff v² = (2/5)k_n√R* δ_max^{5/2}:
    the stiffest it gets); inf for k_t = 0."""
    law = case.contact_model.law
    v = max(fastest_relative_speed(case), 1e-3)
    out = {}
    for name, m_eff, r_eff in _pairs(case):
        a, b = pair_materials(case, name)
        k_n = law.sticking_stiffness(pair_stiffness(case, a, b), m_eff, r_eff, v)
        k_t = tangential_ratio(case, a, b) * k_n
        out[name] = math.pi / math.sqrt(k_t * TANGENTIAL_INERTIA / m_eff) if k_t else math.inf
    return out


def contact_durations(case: Case) -> dict[str, float]:
    """Head-on contact duration of each soft contact kind (granule-hammer, -wall, -granule), s.

    Linear: independent of speed; Hertz (contact stiffness k_n √R*): at the fastest relative
    speed, where it is shortest. Raises ValueError for a restitution the contact model cannot
    reach (e ≤ e⁻² with end = 'force').
    """
    cm = case.contact_model
    law = cm.law
    v = max(fastest_relative_speed(case), 1e-3)
    out = {}
    for name, m_eff, r_eff in _pairs(case):
        a, b = pair_materials(case, name)
        e = case.contact(a, b).restitution
        out[name] = law.duration(pair_stiffness(case, a, b), e, m_eff, r_eff, v, cm.end)
    return out


DAMPING_SCALE = 0.4
"""Steps per contact grow with damping by max(1, DAMPING_SCALE·2πζ/√(1 − ζ²))
(:func:`steps_for_damping`): at the default 50 steps per contact, 20 per dashpot time."""


def steps_for_damping(zeta: float, asked: float) -> float:
    """Steps per contact duration t_c for a contact of damping ratio ζ (Tsuji's α/√5 for
    Hertz): ``asked`` (contact_model.steps_per_contact) times max(1, 0.4·t_c/τ), τ =
    t_c√(1 − ζ²)/(2πζ) the dashpot's time (t_c of a linear contact that ends at zero overlap):
    at the default 50, 20 steps per τ. At t_c/50 alone, e = 0.05 (ζ = 0.69) came out 0.7-1.2 %
    low (second order in the step); this gives it 120 steps; it leaves ζ ≤ 0.37 (e ≥ 0.39 for
    a contact that ends at zero force, e ≥ 0.29 at zero overlap) at 50 (docs/dev/validation.md).
    A factor, not a floor, so that a study of the step (``perga accuracy``) keeps its ladder."""
    return asked * max(1.0, DAMPING_SCALE * 2.0 * math.pi * zeta / math.sqrt(1.0 - zeta**2))


def contact_steps(case: Case, name: str) -> float:
    """Steps per contact duration of the soft contact kind ``name`` (:func:`_pairs`)."""
    cm = case.contact_model
    e = case.contact(*pair_materials(case, name)).restitution
    return steps_for_damping(cm.law.damping_ratio(e, cm.end), cm.steps_per_contact)


@dataclass(frozen=True)
class PairPlan:
    """One soft contact kind of a case as the run takes it: ``contact`` (granule-hammer, -wall,
    -granule), its ``materials``, restitution e, normal ``stiffness`` k_n (N/m linear; (4/3)E*,
    Pa, Hertz, whose contact stiffness is k_n√R*), dimensionless ``damping`` (ζ linear, Tsuji's
    α = √5ζ Hertz), the ``convention`` that gives it from e, the head-on ``duration`` t_c of the
    smallest granule (s; Hertz at the fastest relative speed) and the granule steps it takes,
    k_t/k_n and the tangential half-period of a sticking contact with the steps it takes."""

    contact: str
    materials: tuple[str, str]
    restitution: float
    stiffness: float
    stiffness_unit: str
    damping: float
    convention: str
    duration: float
    steps_per_contact: float
    tangential_ratio: float
    tangential_half_period: float
    """π/ω_t of a sticking contact (:func:`tangential_half_periods`), s."""
    steps_per_tangential_half_period: float


CONVENTIONS = {
    "force": "ζ(e) of a contact that ends when its force returns to zero (Schwager & Pöschel "
    "2007), a larger ζ than the usual ζ = −ln e/√(π² + ln² e)",
    "overlap": "ζ = −ln e/√(π² + ln² e): the contact ends when its overlap returns to zero "
    "(attractive force allowed at the end)",
}
"""How each end criterion (``contact_model.end``) turns e into damping."""


def contact_plan(case: Case, granule_dt: float) -> list[PairPlan]:
    """The soft contacts of ``case`` as taken with granule step ``granule_dt`` (s)."""
    cm = case.contact_model
    law = cm.law
    half_periods = tangential_half_periods(case)
    out = []
    for name, t_c in contact_durations(case).items():
        a, b = pair_materials(case, name)
        e = case.contact(a, b).restitution
        k, damping = pair_stiffness(case, a, b), law.damping(e, cm.end)
        convention, half = CONVENTIONS[cm.end], half_periods[name]
        out.append(
            PairPlan(
                name, (a, b), e, k, law.plan_unit, damping, convention, t_c, t_c / granule_dt,
                tangential_ratio(case, a, b), half, half / granule_dt,
            )
        )  # fmt: skip
    return out


@dataclass(frozen=True)
class StepPlan:
    """The resolved steps of a case, s.

    granule: the step of the granules (soft: perga's kernel; rigid: the Pymunk step);
    machine: the Pymunk step of rotor and hammers (soft: granule·granule_substeps; rigid: the
    same as granule, solver.dt/solver.substeps); contact_duration: the shortest soft contact
    (inf for rigid); tangential_half_period: the shortest half-period of a sticking soft
    contact's tangential oscillation (inf for rigid); tunnelling: the tunnelling bound
    0.5(r + t/2)/v_rel; rotation: the step turning the rotor by MAX_ROTATION_PER_STEP;
    governed_by: what set an automatic step ('given' for a step from solver.dt).
    """

    granule: float
    machine: float
    contact_duration: float
    tangential_half_period: float
    tunnelling: float
    rotation: float
    governed_by: Literal["given", "contact", "tunnelling", "rotation"]


def step_plan(case: Case) -> StepPlan:
    """Resolve solver.dt ('auto' or given) into the granule and machine steps of the case.

    'auto' takes the smallest of t_c/steps_per_contact (more steps for a strongly damped
    contact, :func:`steps_for_damping`) and the tangential half-period/steps_per_contact of
    each soft contact kind, half the tunnelling bound, and the rotor-turn bound (per machine
    step: divided by granule_substeps for soft contacts); a rigid step is then divided by
    solver.substeps (soft contacts take solver.substeps = 1).
    """
    cm, solver = case.contact_model, case.solver
    durations = contact_durations(case) if cm.soft else {}
    half_periods = tangential_half_periods(case) if cm.soft else {}
    t_c = min(durations.values(), default=math.inf)
    resolved = min(
        (
            min(d / contact_steps(case, name), half_periods[name] / cm.steps_per_contact)
            for name, d in durations.items()
        ),
        default=math.inf,
    )
    tunnelling = tunnelling_time_step(
        radius_range(case)[0], thinnest_obstacle(case), fastest_relative_speed(case)
    )
    substeps = cm.granule_substeps if cm.soft else 1
    rotation = MAX_ROTATION_PER_STEP / case.rotor.angular_velocity / substeps
    if solver.dt != "auto":
        step, governed_by = solver.dt, "given"
    else:
        bounds = {
            "contact": resolved,
            "tunnelling": 0.5 * tunnelling,
            "rotation": rotation,
        }
        governed_by = min(bounds, key=bounds.__getitem__)
        step = bounds[governed_by]
    granule = step if cm.soft else step / solver.substeps
    return StepPlan(
        granule=granule,
        machine=granule * substeps,
        contact_duration=t_c,
        tangential_half_period=min(half_periods.values(), default=math.inf),
        tunnelling=tunnelling,
        rotation=rotation * substeps,
        governed_by=governed_by,  # type: ignore[arg-type]
    )
