"""The system a simulation is built from: frozen dataclasses in SI units, independent of the
case-file schema (``perga.case``), which :mod:`perga.model.compile` maps onto them.

Frames: the rotor axis is the origin of the fixed plane frame, ω > 0 turns counter-clockwise.
A hammer's outline is given in its own frame: hinge at the origin, hammer axis along +x. The
hinge sits at ``hinge_radius`` on the rotor at the polar angle ``angle_on_rotor``; the hammer
axis makes ``swing_angle`` (α, rad, counter-clockwise) with the radial line through the hinge.

Units: m, s, kg, rad; velocities m/s; moments of inertia kg·m²; gravity m/s²; torques N·m;
densities kg/m³.
Invalid input raises ``ValueError`` listing every problem found.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar, Literal

import numpy as np

from perga.analytic.common import STANDARD_GRAVITY
from perga.contact.laws import LAWS
from perga.geometry.convex import decompose
from perga.geometry.polygon import clean, counter_clockwise, self_intersection, vertex_tuples
from perga.geometry.wall import circumscribed, wall_pieces
from perga.model.process import ProcessSpec

if TYPE_CHECKING:
    from perga.model.plan import PairPlan, StepPlan

Vec2 = tuple[float, float]
Mount = Literal["hinged", "welded", "free"]


def _raise(owner: str, problems: list[str]) -> None:
    if problems:
        raise ValueError(f"{owner}: " + "; ".join(problems))


def _positive(problems: list[str], name: str, value: float, unit: str = "") -> None:
    if not (math.isfinite(value) and value > 0):
        problems.append(f"{name} must be finite and > 0{' ' + unit if unit else ''} (got {value})")


def _finite_vec(problems: list[str], name: str, value: Vec2) -> None:
    if len(value) != 2 or not all(math.isfinite(c) for c in value):
        problems.append(f"{name} must be two finite numbers (got {value!r})")


@dataclass(frozen=True)
class RotorSpec:
    """A rotor turning at constant angular velocity about the origin.

    angular_velocity: rad/s (>= 0; 0 gives a fixed machine, e.g. a wall test);
    radius: rotor disc radius, m (> 0; geometric, used for output and checks);
    outline: the disc's outline (m, counter-clockwise) when it is not a circle of ``radius``
    (output only: the disc is out of the granules' plane).
    """

    angular_velocity: float
    radius: float
    outline: tuple[Vec2, ...] | None = None

    def __post_init__(self) -> None:
        problems: list[str] = []
        if not (math.isfinite(self.angular_velocity) and self.angular_velocity >= 0):
            problems.append(
                f"angular_velocity must be finite and >= 0 rad/s (got {self.angular_velocity})"
            )
        _positive(problems, "radius", self.radius, "m")
        _raise("rotor", problems)


@dataclass(frozen=True)
class HammerSpec:
    """A hammer: a polygon mounted on the rotor.

    outline: vertices of a simple polygon (m) in the hammer frame (hinge at origin, axis +x),
    stored counter-clockwise without collinear vertices; ``pieces`` are its convex pieces (the
    outline itself when convex; Chipmunk and the soft contacts take convex polygons only);
    mass: kg; moment_about_hinge: I_A, kg·m² (> mass·|centre_of_mass|²);
    centre_of_mass: (m) in the hammer frame; hinge_radius: distance of the hinge from the
    rotor axis, m (>= 0); angle_on_rotor: polar angle of the hinge, rad;
    mount: 'hinged' (free to swing about the hinge), 'welded' (rigidly part of the rotor), or
    'free' (no attachment; for validation scenes: the hammer then moves with ``velocity``);
    material: name looked up in the scene's contact table;
    swing_angle: initial α, rad (hinged/free only; the hammer starts co-rotating with the rotor);
    swing_limit: stops at α = ±swing_limit, rad ('hinged' only; None: no stops);
    velocity: initial centre-of-mass velocity, m/s ('free' only);
    angular_velocity: initial angular velocity, rad/s ('free' only).
    """

    outline: tuple[Vec2, ...]
    mass: float
    moment_about_hinge: float
    centre_of_mass: Vec2
    hinge_radius: float
    angle_on_rotor: float
    mount: Mount
    material: str
    swing_angle: float = 0.0
    swing_limit: float | None = None
    velocity: Vec2 = (0.0, 0.0)
    angular_velocity: float = 0.0
    pieces: tuple[tuple[Vec2, ...], ...] = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "outline", tuple(tuple(map(float, v)) for v in self.outline))
        problems: list[str] = []
        if len(self.outline) < 3:
            problems.append(f"outline needs >= 3 vertices (got {len(self.outline)})")
        for i, vertex in enumerate(self.outline):
            _finite_vec(problems, f"outline[{i}]", vertex)  # type: ignore[arg-type]
        if not problems:
            crossing = self_intersection(self.outline)
            if crossing is not None:
                problems.append(f"outline edges {crossing[0]} and {crossing[1]} cross")
            else:
                outline = clean(counter_clockwise(self.outline))
                object.__setattr__(self, "outline", vertex_tuples(outline))
                pieces = tuple(vertex_tuples(q) for q in decompose(outline))
                object.__setattr__(self, "pieces", pieces)
        _positive(problems, "mass", self.mass, "kg")
        _finite_vec(problems, "centre_of_mass", self.centre_of_mass)
        if not problems:
            arm2 = self.centre_of_mass[0] ** 2 + self.centre_of_mass[1] ** 2
            if not (
                math.isfinite(self.moment_about_hinge)
                and self.moment_about_hinge > self.mass * arm2
            ):
                problems.append(
                    "moment_about_hinge must exceed mass·|centre_of_mass|² = "
                    f"{self.mass * arm2} kg·m² (got {self.moment_about_hinge})"
                )
        if not (math.isfinite(self.hinge_radius) and self.hinge_radius >= 0):
            problems.append(f"hinge_radius must be finite and >= 0 m (got {self.hinge_radius})")
        if self.mount not in ("hinged", "welded", "free"):
            problems.append(f"mount must be 'hinged', 'welded' or 'free' (got {self.mount!r})")
        if self.mount != "free" and (self.velocity != (0.0, 0.0) or self.angular_velocity != 0.0):
            problems.append("velocity and angular_velocity are only for mount 'free'")
        if self.swing_limit is not None and not (
            self.mount == "hinged"
            and 0 < self.swing_limit <= math.pi
            and abs(self.swing_angle) <= self.swing_limit
        ):
            problems.append(
                "swing_limit must be in (0, π] rad, for a hinged hammer, with |swing_angle| "
                f"within it (got {self.swing_limit} for {self.mount!r}, α = {self.swing_angle})"
            )
        if not self.material:
            problems.append("material must be a non-empty name")
        _raise("hammer", problems)

    @property
    def hinge_position(self) -> Vec2:
        """The hinge in the rotor frame (= the fixed frame at t = 0), m."""
        return (
            self.hinge_radius * math.cos(self.angle_on_rotor),
            self.hinge_radius * math.sin(self.angle_on_rotor),
        )

    @property
    def centre_on_rotor(self) -> Vec2:
        """The centre of mass in the rotor frame at the initial swing angle, m."""
        a = self.angle_on_rotor + self.swing_angle
        (hx, hy), (cx, cy) = self.hinge_position, self.centre_of_mass
        return (hx + math.cos(a) * cx - math.sin(a) * cy, hy + math.sin(a) * cx + math.cos(a) * cy)

    @property
    def moment_about_centre(self) -> float:
        """I_C = I_A − M·|c|², kg·m² (parallel-axis theorem)."""
        cx, cy = self.centre_of_mass
        return self.moment_about_hinge - self.mass * (cx * cx + cy * cy)


@dataclass(frozen=True)
class GranuleSpec:
    """A disc granule.

    position (m), velocity (m/s) in the fixed frame; radius (m), mass (kg); material;
    rolls: True gives a disc's moment m r²/2 (it can roll); False gives moment = inf, a sliding
    point that never changes its angular velocity; angular_velocity: initial, rad/s (a sliding
    granule on a rotor face should start with the rotor's ω so that its surface does not slip
    against the face, docs/pymunk.md); bond_force: held at its position (a comb's cell) until the
    force the bond must supply exceeds this, N; None: free; bond_energy: with it, a force above
    bond_force begins a blow, after which the bond breaks if the granule's kinetic energy
    exceeds this, J, taking that much (``perga.contact.soft.kernel`` module doc); inf: none.
    """

    position: Vec2
    velocity: Vec2
    radius: float
    mass: float
    material: str
    rolls: bool = True
    angular_velocity: float = 0.0
    bond_force: float | None = None
    bond_energy: float = math.inf

    def __post_init__(self) -> None:
        problems: list[str] = []
        if self.bond_force is not None and not self.bond_force > 0:
            problems.append(f"bond_force must be > 0 N or None (got {self.bond_force})")
        if not self.bond_energy > 0:
            problems.append(f"bond_energy must be > 0 J (got {self.bond_energy})")
        _finite_vec(problems, "position", self.position)
        _finite_vec(problems, "velocity", self.velocity)
        _positive(problems, "radius", self.radius, "m")
        _positive(problems, "mass", self.mass, "kg")
        if not math.isfinite(self.angular_velocity):
            problems.append(f"angular_velocity must be finite (got {self.angular_velocity})")
        if not self.material:
            problems.append("material must be a non-empty name")
        _raise("granule", problems)

    @property
    def moment(self) -> float:
        """Moment of inertia about the centre, kg·m²: m r²/2 (rolls) or inf (sliding point)."""
        return 0.5 * self.mass * self.radius**2 if self.rolls else math.inf


@dataclass(frozen=True)
class ContactSpec:
    """Contact parameters of one unordered material pair: Newton restitution e in [0, 1] and
    Coulomb friction f >= 0, used exactly (not as a product of per-material values); for soft
    contacts the pair's normal stiffness k_n: N/m (linear) or (4/3)E*, Pa (Hertz: the contact
    stiffness is k_n·√R*, R* from the radii of the contact itself; None for rigid ones) and
    their tangential stiffness over it, k_t/k_n (default 2/7, as LAMMPS; unused by rigid ones)."""

    material_a: str
    material_b: str
    restitution: float
    friction: float
    stiffness: float | None = None
    tangential_ratio: float = 2.0 / 7.0

    def __post_init__(self) -> None:
        problems: list[str] = []
        if not 0.0 <= self.restitution <= 1.0:
            problems.append(f"restitution must be in [0, 1] (got {self.restitution})")
        if not (math.isfinite(self.friction) and self.friction >= 0):
            problems.append(f"friction must be finite and >= 0 (got {self.friction})")
        if self.stiffness is not None:
            _positive(problems, "stiffness", self.stiffness, "N/m or Pa")
        if not (math.isfinite(self.tangential_ratio) and self.tangential_ratio >= 0):
            problems.append(
                f"tangential_ratio must be finite and >= 0 (got {self.tangential_ratio})"
            )
        _raise(f"contact {self.material_a}-{self.material_b}", problems)

    @property
    def key(self) -> frozenset[str]:
        """The unordered pair."""
        return frozenset((self.material_a, self.material_b))


@dataclass(frozen=True)
class ChamberSpec:
    """A static chamber wall around the rotor axis: round, or along an outline.

    radius: inner radius of a round wall, or the nearest point of ``outline`` to the axis, m;
    wall_thickness: m (thick walls stop fast granules tunnelling, docs/pymunk.md); material: name
    in the contact table; segments: number of thick segments whose inner faces touch the
    circle of a round wall (>= 8); outline: the wall's inner outline (m, counter-clockwise,
    around the axis), None for a round wall. Hammers never collide with the wall.
    """

    radius: float
    wall_thickness: float
    material: str
    segments: int = 96
    outline: tuple[Vec2, ...] | None = None

    def __post_init__(self) -> None:
        problems: list[str] = []
        _positive(problems, "radius", self.radius, "m")
        _positive(problems, "wall_thickness", self.wall_thickness, "m")
        if not (isinstance(self.segments, int) and self.segments >= 8):
            problems.append(f"segments must be an integer >= 8 (got {self.segments!r})")
        if not self.material:
            problems.append("material must be a non-empty name")
        _raise("chamber", problems)

    @property
    def outer_radius(self) -> float:
        """The farthest point of the wall's inner outline from the axis, m."""
        if self.outline is None:
            return self.radius
        return float(np.hypot(*np.array(self.outline).T).max())

    def inner_outline(self) -> np.ndarray:
        """The wall's inner outline, m: the chamber's outline, or the circumscribed polygon of
        a round wall's circle (``segments`` sides)."""
        if self.outline is not None:
            return np.array(self.outline, dtype=float)
        return circumscribed(self.radius, self.segments)

    def pieces(self) -> tuple[list[np.ndarray], np.ndarray]:
        """The wall's convex pieces and its outer outline, m
        (:func:`perga.geometry.wall.wall_pieces`)."""
        return wall_pieces(self.inner_outline(), self.wall_thickness)


@dataclass(frozen=True)
class FloorFrictionSpec:
    """Coulomb friction of the floor under a horizontal rotor: deceleration friction·gravity
    (m/s²) opposing a granule's velocity relative to the floor, which either turns with the
    rotor ('corotating': floor velocity ω × r) or is at rest ('stationary')."""

    floor: Literal["corotating", "stationary"]
    friction: float
    gravity: float = STANDARD_GRAVITY

    def __post_init__(self) -> None:
        problems: list[str] = []
        if self.floor not in ("corotating", "stationary"):
            problems.append(f"floor must be 'corotating' or 'stationary' (got {self.floor!r})")
        if not (math.isfinite(self.friction) and self.friction >= 0):
            problems.append(f"friction must be finite and >= 0 (got {self.friction})")
        _positive(problems, "gravity", self.gravity, "m/s²")
        _raise("floor friction", problems)


@dataclass(frozen=True)
class AirDragSpec:
    """Quadratic air drag F = ½ ρ C_d A |v| v on every granule, air at rest.

    air_density ρ: kg/m³; drag_coefficient C_d: -; thickness t: m, the disc granule's extent
    out of the plane, so that its projected area seen edge-on is A = 2 r t (m²).
    """

    air_density: float
    drag_coefficient: float
    thickness: float

    def __post_init__(self) -> None:
        problems: list[str] = []
        _positive(problems, "air_density", self.air_density, "kg/m³")
        _positive(problems, "drag_coefficient", self.drag_coefficient)
        _positive(problems, "thickness", self.thickness, "m")
        _raise("air drag", problems)


@dataclass(frozen=True)
class DriveSpec:
    """A rotor of finite inertia driven by a motor that holds ``RotorSpec.angular_velocity``.

    inertia: the rotor's moment about its axis without its hammers, kg·m² (welded hammers add
    their own moments about the axis); torque_limit: the largest motor torque, N·m.
    """

    inertia: float
    torque_limit: float

    def __post_init__(self) -> None:
        problems: list[str] = []
        _positive(problems, "inertia", self.inertia, "kg·m²")
        _positive(problems, "torque_limit", self.torque_limit, "N·m")
        _raise("drive", problems)


@dataclass(frozen=True)
class EffectsSpec:
    """Optional physics; each ``None`` effect is not built at all (no handler, velocity
    function, constraint or per-step work).

    floor_friction: horizontal rotor only (System.gravity must be zero); air_drag;
    hinge_friction: Coulomb torque at every hinge, N·m (> 0); drive: finite rotor inertia.
    """

    floor_friction: FloorFrictionSpec | None = None
    air_drag: AirDragSpec | None = None
    hinge_friction: float | None = None
    drive: DriveSpec | None = None

    def __post_init__(self) -> None:
        problems: list[str] = []
        if self.hinge_friction is not None:
            _positive(problems, "hinge_friction", self.hinge_friction, "N·m")
        _raise("effects", problems)


@dataclass(frozen=True)
class RigidContactSpec:
    """Rigid granule contacts: Pymunk's impulses, restitution and friction exact per impact
    (:mod:`perga.contact.rigid`); the granules move with the machine's step (one substep)."""

    kind: ClassVar[str] = "rigid"
    model: ClassVar[str] = "impulse"
    substeps: ClassVar[int] = 1
    threads: ClassVar[int | None] = 1


@dataclass(frozen=True)
class SoftContactSpec:
    """Soft granule contacts (:mod:`perga.contact.soft`) instead of Pymunk impulses.

    model: the contact law's name in :data:`perga.contact.laws.LAWS` ('linear', 'hertz', ...;
    each pair's k_n: :attr:`ContactSpec.stiffness`);
    tangential_damping: ratio ζ_t of the tangential dashpot
    −2ζ_t√(k_t m_eff)·v_t, in [0, 1); rolling: rolling-resistance coefficient μ_r;
    end: 'force' (force clamped at zero) or 'overlap'; substeps: granule steps of
    ``System.dt`` per Pymunk step of rotor and hammers (>= 1); threads: the kernel's threads
    asked for (None: "auto", :mod:`perga.contact.soft.threads`). Damping per pair comes from
    the pair's restitution, friction from the pair's friction.
    """

    model: str
    tangential_damping: float = 0.0
    rolling: float = 0.0
    end: Literal["force", "overlap"] = "force"
    substeps: int = 1
    threads: int | None = None

    def __post_init__(self) -> None:
        problems: list[str] = []
        if self.model not in LAWS:
            problems.append(
                f"model must be a contact law, one of {', '.join(LAWS)} (got {self.model!r})"
            )
        if not (math.isfinite(self.rolling) and self.rolling >= 0):
            problems.append(f"rolling must be finite and >= 0 (got {self.rolling})")
        if not 0.0 <= self.tangential_damping < 1.0:
            problems.append(f"tangential_damping must be in [0, 1) (got {self.tangential_damping})")
        if self.end not in ("force", "overlap"):
            problems.append(f"end must be 'force' or 'overlap' (got {self.end!r})")
        if not (isinstance(self.substeps, int) and self.substeps >= 1):
            problems.append(f"substeps must be an integer >= 1 (got {self.substeps!r})")
        _raise("soft contacts", problems)

    @property
    def kind(self) -> str:
        """The contact model as the case names it (``contact_model.kind``): the law's name,
        which :func:`perga.contact.contact_model` takes to the soft model."""
        return self.model


@dataclass(frozen=True)
class DrawingSpec:
    """Out-of-plane sizes of the parts for the 3-D view of the output (:mod:`perga.output.
    vtk3d`), m; never used by the engine. Carried by the system because the recorders see the
    system and its frames only: a ``System`` with a drawing is what asks for the 3-D view.

    hammer_thickness: one per hammer; rotor_thickness: the disc's; chamber_height: the wall's;
    granule_thickness: every granule's (drawn as cylinders).
    """

    hammer_thickness: tuple[float, ...]
    rotor_thickness: float
    chamber_height: float
    granule_thickness: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "hammer_thickness", tuple(map(float, self.hammer_thickness)))
        problems: list[str] = []
        for k, t in enumerate(self.hammer_thickness):
            _positive(problems, f"hammer_thickness[{k}]", t, "m")
        for name in ("rotor_thickness", "chamber_height", "granule_thickness"):
            _positive(problems, name, getattr(self, name), "m")
        _raise("drawing", problems)


@dataclass(frozen=True)
class System:
    """Everything a simulation is built from.

    granule_dt: the granules' time step, s (> 0); the machine (rotor and hammers in Pymunk)
    steps ``machine_dt`` = granule_dt · contact_model.substeps; iterations: Chipmunk solver
    iterations (>= 1); gravity: in-plane gravity, m/s² (zero for a horizontal rotor);
    granule_collisions: whether granules collide with each other; chamber: the wall, or None;
    effects: optional physics; contact_model: :class:`RigidContactSpec` (Pymunk's impulses) or
    :class:`SoftContactSpec`; drawing: sizes for the 3-D view of the output
    (:class:`DrawingSpec`), or None for none; plan: the time-step plan the steps came from
    (:class:`perga.model.plan.StepPlan`), None for a system made by hand; pairs: each soft
    contact kind as the steps take it (:class:`perga.model.plan.PairPlan`; none for rigid
    contacts or a system made by hand); process: feed, outlet
    and damage (:mod:`perga.model.process`), each None unless the system has it. Every material pair
    that can touch must be in ``contacts`` exactly once. Hammers never collide with each other,
    with the rotor or with the chamber wall.
    """

    rotor: RotorSpec
    hammers: tuple[HammerSpec, ...]
    granules: tuple[GranuleSpec, ...]
    contacts: tuple[ContactSpec, ...]
    granule_dt: float
    iterations: int = 10
    gravity: Vec2 = (0.0, 0.0)
    granule_collisions: bool = False
    chamber: ChamberSpec | None = None
    effects: EffectsSpec = EffectsSpec()
    contact_model: RigidContactSpec | SoftContactSpec = RigidContactSpec()
    drawing: DrawingSpec | None = None
    plan: StepPlan | None = None
    pairs: tuple[PairPlan, ...] = ()
    process: ProcessSpec = field(default_factory=ProcessSpec)
    _table: dict[frozenset[str], ContactSpec] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("hammers", "granules", "contacts"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        problems: list[str] = []
        _positive(problems, "granule_dt", self.granule_dt, "s")
        if not (isinstance(self.iterations, int) and self.iterations >= 1):
            problems.append(f"iterations must be an integer >= 1 (got {self.iterations!r})")
        _finite_vec(problems, "gravity", self.gravity)
        if self.effects.floor_friction is not None and tuple(self.gravity) != (0.0, 0.0):
            problems.append("floor_friction needs a horizontal rotor (gravity must be (0, 0))")
        table: dict[frozenset[str], ContactSpec] = {}
        for contact in self.contacts:
            if contact.key in table:
                problems.append(f"contact pair {sorted(contact.key)} is given more than once")
            table[contact.key] = contact
        for pair in sorted(self.touching_pairs(), key=sorted):
            if pair not in table:
                problems.append(f"no contact parameters for materials {sorted(pair)}")
        for pair in sorted(set(table) - self.touching_pairs(), key=sorted):
            problems.append(f"contact pair {sorted(pair)} is unused by this scene")
        soft = isinstance(self.contact_model, SoftContactSpec)
        for contact in self.contacts:
            if soft and contact.stiffness is None:
                problems.append(f"contact pair {sorted(contact.key)} needs a soft stiffness")
        if self.drawing is not None and len(self.drawing.hammer_thickness) != len(self.hammers):
            problems.append(
                f"drawing.hammer_thickness has {len(self.drawing.hammer_thickness)} values for "
                f"{len(self.hammers)} hammers"
            )
        _raise("scene", problems)
        object.__setattr__(self, "_table", table)

    def touching_pairs(self) -> set[frozenset[str]]:
        """Material pairs that can come into contact in this scene."""
        granule_materials = self.granule_materials
        hammer_materials = {h.material for h in self.hammers}
        pairs = {frozenset((g, h)) for g in granule_materials for h in hammer_materials}
        if self.granule_collisions:
            pairs |= {frozenset((a, b)) for a in granule_materials for b in granule_materials}
        if self.chamber is not None:
            pairs |= {frozenset((g, self.chamber.material)) for g in granule_materials}
        return pairs

    @property
    def granule_materials(self) -> set[str]:
        """The materials of the granules present and of those a feed brings."""
        feed = self.process.feed
        return {g.material for g in self.granules} | ({feed.material} if feed else set())

    @property
    def has_bonds(self) -> bool:
        """Whether any granule, present or fed, is held in a cell by a bond."""
        feed = self.process.feed
        return any(g.bond_force is not None for g in self.granules) or (
            feed is not None and feed.bond_force is not None
        )

    @property
    def machine_dt(self) -> float:
        """The machine's step (Pymunk's, of rotor and hammers), s: granule_dt · substeps."""
        return self.granule_dt * self.contact_model.substeps

    def contact(self, material_a: str, material_b: str) -> ContactSpec:
        """The contact parameters of a material pair (order does not matter)."""
        return self._table[frozenset((material_a, material_b))]
