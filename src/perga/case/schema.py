"""The case-file schema: pydantic models whose fields carry SI units and allowed ranges.

Unknown keys are errors (``extra="forbid"``). Each field's description states its unit and
range; ``perga schema`` prints the JSON Schema built from these models.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, get_args, get_origin

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError, core_schema

from perga.analytic.hammer import PlateHammer
from perga.contact.laws import LAWS, contact_law

if TYPE_CHECKING:
    from perga.contact.laws.base import ContactLaw


class Strict(BaseModel):
    """Base of every case-file table: unknown keys are errors, values are immutable, and a number
    is a finite number: a string ("1500") or a boolean where only numbers are allowed is an
    error, not converted (pydantic's lax mode would take both), and so are nan and ±inf."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _numbers_are_numbers(cls, data: object) -> object:
        if isinstance(data, dict):
            for name, field in cls.model_fields.items():
                value = data.get(name)
                annotation = field.annotation
                if _mentions_number(annotation) and _has_text_or_bool(
                    value, _admits_text(annotation)
                ):
                    raise PydanticCustomError(
                        NOT_A_NUMBER,
                        "must be a number (numbers in a list), written without quotes",
                        {"field": name, "value": value},
                    )
        return data


LONGEST = 3600.0
"""Longest simulated time a case may ask for, s (solver.duration), and so the longest interval
between two frames or checkpoints."""

FINEST_STEP = 1e-12
"""Smallest time step a case may give, s: the automatic step's least (a contact of the shortest
duration, 1e-9 s, resolved by the most steps, 1000)."""

NOT_A_NUMBER = "not_a_number"
"""The error type of a string or boolean given for a number (its key and value in ``ctx``)."""


def _mentions_number(annotation: object) -> bool:
    """Whether a field's type allows a number anywhere (float, int, in a union or container)."""
    if annotation in (float, int):
        return True
    return any(_mentions_number(a) for a in get_args(annotation))


def _admits_text(annotation: object) -> bool:
    """Whether a field's type allows a string anywhere (str, a Literal of strings)."""
    if annotation is str:
        return True
    if get_origin(annotation) is Literal:
        return any(isinstance(a, str) for a in get_args(annotation))
    return any(_admits_text(a) for a in get_args(annotation))


def _has_text_or_bool(value: object, text_allowed: bool) -> bool:
    """Whether ``value`` is, or holds (in lists and tuples), a bool or a disallowed string."""
    if isinstance(value, bool) or (isinstance(value, str) and not text_allowed):
        return True
    if isinstance(value, list | tuple):
        return any(_has_text_or_bool(v, text_allowed) for v in value)
    return False


class PartFile(Strict):
    """A rotor disc or chamber drawn in a geometry file (geometry/), in the rotor frame (the
    rotor axis at the origin). Relative paths are relative to the case file."""

    kind: Literal["file"]
    path: str = Field(description="geometry file, relative to the case file or absolute")
    units: Literal["m", "cm", "mm"] = Field("mm", description="length unit of the file")


class Rotor(Strict):
    """[rotor]: the rotor turning at constant angular velocity."""

    plane: Literal["horizontal", "vertical"] = Field(
        "horizontal",
        description="plane of rotation: 'horizontal' (vertical axis, gravity presses granules "
        "on the floor) or 'vertical' (gravity acts in the plane)",
    )
    omega: float | None = Field(
        None, ge=1e-6, le=2000, description="angular velocity, rad/s, in [1e-6, 2000]; or give rpm"
    )
    rpm: float | None = Field(
        None, ge=1e-5, le=20000, description="angular velocity, rev/min, in [1e-5, 20000]; or omega"
    )
    radius: float = Field(
        0.15, ge=1e-3, le=5, description="rotor disc radius, m, in [1e-3, 5]; omit with a shape"
    )
    shape: PartFile | None = Field(
        None,
        description="the rotor disc from a mesh (its section by the rotor plane) or an outline "
        "with its hinge holes: sets the disc radius, and every hammer's hinge must sit at a hole",
    )
    inertia: float | None = Field(
        None,
        ge=1e-9,
        description="moment of inertia about the axis, kg·m², >= 1e-9; omit for a rotor held at "
        "constant ω (needs the rotor_inertia effect)",
    )
    torque_limit: float | None = Field(
        None, ge=1e-6, description="drive torque limit, N·m, >= 1e-6 (with inertia)"
    )

    @model_validator(mode="after")
    def _one_speed(self) -> Rotor:
        if (self.omega is None) == (self.rpm is None):
            raise ValueError("give exactly one of omega (rad/s) or rpm (rev/min)")
        if self.shape is not None and "radius" in self.model_fields_set:
            raise ValueError("radius: the disc's shape file sets it; omit radius")
        return self

    @property
    def angular_velocity(self) -> float:
        """ω, rad/s."""
        return self.omega if self.omega is not None else self.rpm * 2 * math.pi / 60


class PlateShape(Strict):
    """[hammers.shape] with kind = "plate": a rectangular plate hinged on its axis."""

    kind: Literal["plate"] = "plate"
    length: float = Field(
        ge=1e-3, le=2, description="length along the hammer axis, m, in [1e-3, 2]"
    )
    width: float = Field(ge=1e-4, le=1, description="width across the axis, m, in [1e-4, 1]")
    hinge_offset: float = Field(
        0.0, ge=0, description="distance from the inner end to the hinge, m, in [0, length/2)"
    )
    strike_distance: float | None = Field(
        None,
        ge=1e-4,
        description="distance a from the hinge to the striking point K, m, in [1e-4, length − "
        "hinge_offset]; default: the centre of percussion clipped to the plate",
    )


class FileShape(Strict):
    """[hammers.shape] with kind = "file": the hammer's shape from a geometry file (geometry/),
    drawn in the hammer frame (hinge at the origin, hammer axis along +x).

    A closed mesh (.stl, .obj: mass properties from the mesh and the material's density, the
    outline its section by the rotor plane) or a 2-D outline (.txt points, .svg, .dxf: extruded
    to ``thickness``). Relative paths are relative to the case file. A concave outline is
    split into convex pieces.
    """

    kind: Literal["file"]
    path: str = Field(description="geometry file, relative to the case file or absolute")
    units: Literal["m", "cm", "mm"] = Field("mm", description="length unit of the file")
    thickness: float | None = Field(
        None,
        ge=1e-4,
        le=1,
        description="out-of-plane thickness, m, in [1e-4, 1]: outlines only (meshes: their own)",
    )
    height: float | None = Field(
        None,
        description="meshes: height z of the rotor plane in the file's frame, m after "
        "scaling; default half-way up the mesh",
    )


HammerShape = Annotated[PlateShape | FileShape, Field(discriminator="kind")]


class Hammers(Strict):
    """[hammers]: identical hammers spaced evenly around the rotor."""

    count: int = Field(4, ge=1, le=64, description="number of hammers, in [1, 64]")
    mass: float | None = Field(
        None,
        ge=1e-6,
        le=50,
        description="mass of one hammer, kg, in [1e-6, 50]: plates; a file shape's mass follows "
        "from its geometry and material density",
    )
    hinge_radius: float = Field(
        ge=0, le=5, description="radius R of the hinge (or weld) point, m, in [0, 5]"
    )
    mount: Literal["hinged", "welded", "free"] = Field(
        "hinged",
        description="'hinged' (free to swing on a pivot), 'welded' to the rotor, or 'free' "
        "(not attached: calibration scenes, e.g. a two-body impact; moves with velocity)",
    )
    swing_angle: float = Field(
        0.0,
        ge=-3.1416,
        le=3.1416,
        description="initial angle α of each hammer to the radial "
        "line through its hinge, rad, in [−π, π] (hinged and free hammers)",
    )
    swing_limit: float | None = Field(
        None,
        ge=1e-3,
        le=3.1416,
        description="stops of a hinged hammer: |α| <= swing_limit, rad, in [1e-3, π]; default: "
        "free to swing all round",
    )
    velocity: tuple[float, float] = Field(
        (0.0, 0.0), description="initial centre-of-mass velocity of a free hammer, m/s"
    )
    material: str = Field("steel", description="name of a [materials] entry")
    angles: tuple[float, ...] | None = Field(
        None, description="hinge angles on the rotor, rad, one per hammer; default: evenly spaced"
    )
    hinge_friction: float = Field(
        0.0, ge=0, le=100, description="Coulomb friction torque at the hinge, N·m, in [0, 100]"
    )
    shape: HammerShape

    @model_validator(mode="after")
    def _hinge_on_plate(self) -> Hammers:
        if not isinstance(self.shape, PlateShape):
            if self.mass is not None:
                raise ValueError("mass: a file shape's mass follows from its geometry; omit it")
            return self
        if self.mass is None:
            raise ValueError("mass: a plate hammer needs its mass (kg)")
        if self.shape.hinge_offset >= self.shape.length / 2:
            raise ValueError(
                f"shape.hinge_offset must be < length/2 = {self.shape.length / 2} m "
                f"(got {self.shape.hinge_offset})"
            )
        return self

    def plate(self, density: float) -> PlateHammer:
        """The plate hammer (thickness from mass and density, kg/m³)."""
        s = self.shape
        thickness = self.mass / (density * s.length * s.width)
        return PlateHammer(s.length, s.width, thickness, density, s.hinge_offset)


class ExplicitPlacement(Strict):
    """[granules.placement] kind = "explicit": every granule's position (and velocity and
    spin; perga run --from RUN writes one from a run's frame)."""

    kind: Literal["explicit"]
    positions: list[tuple[float, float]] = Field(
        min_length=1, description="centre of each granule, m, in the fixed frame"
    )
    velocities: list[tuple[float, float]] | None = Field(
        None, description="velocity of each granule, m/s; default: at rest"
    )
    angular_velocities: list[float] | None = Field(
        None, description="angular velocity of each granule, rad/s; default: not spinning"
    )
    overlap: float = Field(
        0.0,
        ge=0.0,
        le=0.01,
        description="largest overlap allowed at the start, m, in [0, 0.01] and below half the "
        "smallest radius: of two granules, or of a granule with the wall or a hammer (a "
        "settled bed's resting contacts; perga run --from sets its run's largest)",
    )


class RingPlacement(Strict):
    """[granules.placement] kind = "ring": evenly spaced on a circle about the axis."""

    kind: Literal["ring"]
    radius: float = Field(ge=1e-4, le=5, description="ring radius, m, in [1e-4, 5]")
    phase: float = Field(0.0, description="angle of the first granule, rad")


class RandomPlacement(Strict):
    """[granules.placement] kind = "random": a non-overlapping random pack in an annulus."""

    kind: Literal["random"]
    inner_radius: float = Field(ge=0, le=5, description="inner radius of the annulus, m")
    outer_radius: float = Field(ge=1e-4, le=5, description="outer radius of the annulus, m")
    seed: int | None = Field(
        None, ge=0, description="seed of the random pack, >= 0; default: solver.seed"
    )


class ShotPlacement(Strict):
    """[granules.placement] kind = "shot": one granule fired at a face, the scene of a rebound
    test (calibration of restitution and friction). ``target = "hammer"``: the leading face of
    hammer 0, the hammer outline's edge of largest y in the hammer's frame (a plate's
    y = width/2), facing the direction of rotation; the path meets it at ``along`` and its
    tangential component points outward along the hammer's axis. ``target = "wall"``: the
    chamber wall's flat edge that the ray from the axis at the angle ``at`` meets (its
    material the chamber's), met there; the tangential component points counter-clockwise."""

    kind: Literal["shot"]
    speed: float = Field(
        ge=1e-3, le=200, description="speed relative to the face, m/s, in [1e-3, 200]"
    )
    target: Literal["hammer", "wall"] = Field(
        "hammer",
        description="what the granule is fired at: 'hammer' (hammer 0's leading "
        "face) or 'wall' (a flat edge of the chamber wall, in the chamber's material)",
    )
    at: float | None = Field(
        None,
        ge=-7,
        le=7,
        description="target = 'wall': the direction from the axis of the "
        "point aimed at on the wall, rad, in [-7, 7]; default 0",
    )
    angle: float = Field(
        0.0,
        ge=0,
        le=1.5708,
        description="angle of the path, rad: of incidence from the face's "
        "normal, in [0, 1.5], or (angle_from = 'surface') from the face, in [0.0708, 1.5708]",
    )
    angle_from: Literal["normal", "surface"] = Field(
        "normal",
        description="what angle is measured from: the face's normal (incidence, as "
        "most rebound tests report it) or its surface (grazing angle)",
    )
    spin: float = Field(
        0.0, ge=-1e5, le=1e5, description="initial angular velocity, rad/s (counter-clockwise > 0)"
    )
    along: float | None = Field(
        None,
        ge=1e-4,
        description="where the path meets the face, m from the hinge along the "
        "hammer's axis; default: the middle of the face",
    )
    gap: float = Field(
        0.001, ge=1e-6, le=0.1, description="distance the granule flies before it touches, m"
    )

    @model_validator(mode="after")
    def _aim(self) -> ShotPlacement:
        if self.incidence > 1.5:
            raise ValueError(
                f"angle = {self.angle} rad from the surface is an incidence of "
                f"{self.incidence:.4g} rad from the normal: at most 1.5 (angle >= 0.0708)"
            )
        if self.target == "wall" and self.along is not None:
            raise ValueError("along places a shot on a hammer face; a wall shot aims with at")
        if self.target == "hammer" and self.at is not None:
            raise ValueError(
                "at aims a shot at the wall (target = 'wall'); a hammer shot uses along"
            )
        return self

    @property
    def incidence(self) -> float:
        """The angle of incidence from the face's normal, rad."""
        return self.angle if self.angle_from == "normal" else math.pi / 2 - self.angle


class CombPlacement(Strict):
    """[granules.placement] kind = "comb": the granules sit in the cells of a comb piece, a
    hexagonal array of cells (rows of ``columns`` cells, every other row shifted by half a
    pitch) centred at ``centre`` and turned by ``angle``; a granule of a material with a
    ``detachment_force`` is held in its cell until the force on it exceeds that, or with a
    ``detachment_energy`` until a blow leaves it more than that energy."""

    kind: Literal["comb"]
    centre: tuple[float, float] = Field(description="centre of the comb piece, m")
    rows: int = Field(ge=1, le=1000, description="rows of cells, in [1, 1000]")
    columns: int = Field(ge=1, le=1000, description="cells per row, in [1, 1000]")
    pitch: float = Field(
        ge=1e-5,
        le=0.05,
        description="distance between neighbouring cells' centres, m: a worker "
        "cell's width across flats plus its wall, 5.2-5.4 mm in bee comb",
    )
    angle: float = Field(0.0, description="turn of the piece, rad (rows along +x at 0)")


Placement = Annotated[
    ExplicitPlacement | RingPlacement | RandomPlacement | ShotPlacement | CombPlacement,
    Field(discriminator="kind"),
]


class SizeDistribution(Strict):
    """[granules.size]: granule radii drawn from a distribution (seeded by ``solver.seed``),
    by number or by mass. ``uniform`` between ``low`` and ``high``; ``normal`` with ``mean``
    and ``sd``, ``lognormal`` with ``median`` and ``sigma`` (of ln r), both cut to
    [``low``, ``high``]; ``table``: the ``radii`` with their ``fractions`` (summing to 1). By
    mass, the fractions (or the density) are of mass: a granule of radius r weighs
    ρπr²·thickness, so its number weight is the mass weight over r²."""

    kind: Literal["uniform", "normal", "lognormal", "table"]
    basis: Literal["number", "mass"] = Field("number", description="fractions of number or mass")
    low: float | None = Field(None, ge=1e-5, le=0.05, description="smallest radius, m")
    high: float | None = Field(None, ge=1e-5, le=0.05, description="largest radius, m")
    mean: float | None = Field(None, ge=1e-5, le=0.05, description="normal: mean radius, m")
    sd: float | None = Field(None, ge=1e-7, le=0.05, description="normal: standard deviation, m")
    median: float | None = Field(None, ge=1e-5, le=0.05, description="lognormal: median radius, m")
    sigma: float | None = Field(
        None, ge=1e-4, le=3, description="lognormal: sd of ln r, in [1e-4, 3]"
    )
    radii: list[float] | None = Field(None, min_length=1, description="table: radii, m")
    fractions: list[float] | None = Field(None, min_length=1, description="table: fractions")

    @model_validator(mode="after")
    def _parameters(self) -> SizeDistribution:
        need = {
            "uniform": ("low", "high"),
            "normal": ("mean", "sd", "low", "high"),
            "lognormal": ("median", "sigma", "low", "high"),
            "table": ("radii", "fractions"),
        }[self.kind]
        missing = [n for n in need if getattr(self, n) is None]
        if missing:
            raise ValueError(f"kind '{self.kind}' needs {', '.join(missing)}")
        extra = [
            n
            for n in ("low", "high", "mean", "sd", "median", "sigma", "radii", "fractions")
            if n not in need and getattr(self, n) is not None
        ]
        if extra:
            raise ValueError(f"kind '{self.kind}' takes no {', '.join(extra)}")
        if self.low is not None and self.high is not None and not self.low < self.high:
            raise ValueError(f"needs low < high (got {self.low} and {self.high} m)")
        if self.kind == "table":
            assert self.radii is not None and self.fractions is not None
            if len(self.radii) != len(self.fractions):
                raise ValueError("radii and fractions need one entry each per size")
            if any(not 0 < r <= 0.05 for r in self.radii):
                raise ValueError("radii must be in (0, 0.05] m")
            if any(f < 0 for f in self.fractions) or abs(sum(self.fractions) - 1.0) > 1e-9:
                raise ValueError(
                    f"fractions must be >= 0 and sum to 1 (sum {sum(self.fractions):.12g})"
                )
        return self


class Granules(Strict):
    """[granules]: bee-bread granules (discs in the plane)."""

    count: int = Field(1, ge=1, le=1_000_000, description="number of granules, in [1, 1e6]")
    radius: float = Field(
        ge=1e-5,
        le=0.05,
        description="disc radius, m, in [1e-5, 0.05]; with size: the largest "
        "radius a time step and the checks plan for",
    )
    size: SizeDistribution | None = Field(
        None, description="radii from a distribution (needs thickness); default: all radius"
    )
    mass: float | None = Field(
        None, ge=1e-12, le=0.1, description="mass of one granule, kg, in [1e-12, 0.1]; or thickness"
    )
    thickness: float | None = Field(
        None,
        ge=1e-5,
        le=0.1,
        description="out-of-plane length of a granule, m, in [1e-5, 0.1]: mass = density·πr²·"
        "thickness from its material; or give mass",
    )
    material: str = Field("beebread", description="name of a [materials] entry")
    rolls: bool = Field(
        True, description="true: a disc that turns (I = m r²/2); false: a sliding point (I = ∞)"
    )
    placement: Placement | None = Field(
        None, description="where the granules start (needed by perga run, not by paper-check)"
    )

    @model_validator(mode="after")
    def _mass_or_thickness(self) -> Granules:
        if (self.mass is None) == (self.thickness is None):
            raise ValueError("give exactly one of mass (kg) or thickness (m)")
        if self.size is not None and self.thickness is None:
            raise ValueError("size: granules of several sizes need thickness (m), not mass")
        return self


class Breakage(Strict):
    """[materials.NAME.breakage]: the Vogel & Peukert (2003) breakage master curve,
    S = 1 − exp(−f_mat · x · k · (W − W_min)) for an impact of mass-specific energy W > W_min,
    x the granule's size (its diameter) and k impacts so far."""

    f_mat: float = Field(ge=1e-6, le=100, description="material strength parameter, kg/(J·m)")
    w_min: float = Field(ge=0, le=1e4, description="threshold mass-specific energy, J/kg")


class Material(Strict):
    """[materials.NAME]."""

    density: float = Field(ge=1, le=30000, description="density, kg/m³, in [1, 30000]")
    youngs_modulus: float | None = Field(
        None,
        ge=1e3,
        le=2e12,
        description="Young's modulus E, Pa, in [1e3, 2e12]: with poisson_ratio, the Hertz "
        "stiffness of each pair, (4/3)E*·√R* with 1/E* = (1 − ν_a²)/E_a + (1 − ν_b²)/E_b",
    )
    poisson_ratio: float | None = Field(
        None, ge=-0.99, le=0.5, description="Poisson's ratio ν, in [-0.99, 0.5]"
    )
    detachment_force: float | None = Field(
        None,
        ge=1e-9,
        le=1e4,
        description="force that pulls a granule of this material out of its "
        "comb cell, N, in [1e-9, 1e4] (with detachment_energy: the force that begins a blow); "
        "none: granules are not held",
    )
    detachment_energy: float | None = Field(
        None,
        ge=1e-9,
        le=100.0,
        description="energy a blow must leave in a granule of this material to pull it out of "
        "its comb cell, J, in [1e-9, 100]: a force above detachment_force begins a blow, in "
        "which the granule moves freely; after it the bond breaks if the granule's kinetic "
        "energy exceeds this, and takes this much, else it stops the granule; none: the "
        "granule goes as soon as the force exceeds detachment_force (at an impact a force set "
        "by the contact's stiffness or the step)",
    )
    breakage: Breakage | None = Field(None, description="breakage parameters (damage)")

    @model_validator(mode="after")
    def _bond_whole(self) -> Material:
        if self.detachment_energy is not None and self.detachment_force is None:
            raise ValueError(
                "detachment_energy needs a detachment_force (the force that begins a blow)"
            )
        return self


class ContactPair(Strict):
    """[[contacts]]: restitution and friction of one pair of materials; with soft contacts
    also, if it differs from the others, the pair's own stiffness (by ``duration`` or
    ``stiffness``, as in [contact_model], which the other pairs take)."""

    pair: tuple[str, str] = Field(description="two [materials] names (order does not matter)")
    restitution: float = Field(ge=0, le=1, description="coefficient of restitution e, in [0, 1]")
    friction: float = Field(ge=0, le=2, description="Coulomb friction coefficient f, in [0, 2]")
    duration: float | None = Field(
        None,
        ge=1e-9,
        le=0.01,
        description="soft contacts: this pair's contact duration t_c, s, in [1e-9, 0.01]: that "
        "of a granule striking a rigid wall head-on with this pair's restitution (hertz: at "
        "the fastest relative speed); sets this pair's k_n instead of [contact_model]'s",
    )
    stiffness: float | None = Field(
        None,
        ge=1,
        description="soft contacts: this pair's normal stiffness k_n, >= 1: N/m (linear) or "
        "(4/3)E*, Pa (hertz), instead of [contact_model]'s",
    )

    @model_validator(mode="after")
    def _one_stiffness(self) -> ContactPair:
        if self.duration is not None and self.stiffness is not None:
            raise ValueError("give this pair's duration (s) or its stiffness, not both")
        return self


class PaperStudy(Strict):
    """[paper]: the inputs of ``perga paper-check`` that the paper states itself."""

    x0: float = Field(0.08, ge=1e-4, description="initial displacement after impact, m")
    decay_times: tuple[float, float] = Field(
        (0.02, 0.05), description="times of the quoted decays, s"
    )
    decay_fractions: tuple[float, float] = Field(
        (0.6, 0.8), description="quoted minimum fractional decreases of x at decay_times"
    )
    final_radius: float = Field(0.02, ge=1e-4, description="r must fall below this by t2, m")
    efficiency_hammer_masses: tuple[float, float, float] = Field(
        (0.005, 0.1, 0.2), description="hammer masses of the quoted efficiencies, kg"
    )
    efficiency_values: tuple[float, float, float] = Field(
        (0.0075, 0.001, 0.0005),
        description="quoted efficiencies (0.7-0.8 %, 0.1 %, below 0.05 %) as fractions",
    )
    successive_radii: tuple[float, ...] = Field(
        (0.080, 0.045, 0.028, 0.015), description="radii after successive impacts, m"
    )
    successive_loss_by_third: float = Field(
        0.7, description="quoted minimum fraction of energy dissipated by the third impact"
    )
    loss_per_impact: float = Field(
        0.2, description="quoted minimum fraction of granule KE lost in one impact at e"
    )


class Chamber(Strict):
    """[chamber]: the wall around the rotor: round (``radius``) or drawn in a file (``shape``,
    its inner outline; a closed mesh gives its section's outline)."""

    radius: float | None = Field(
        None, ge=1e-3, le=5, description="inner radius of a round wall, m, in [1e-3, 5]; or a shape"
    )
    shape: PartFile | None = Field(
        None, description="the wall's inner outline from a geometry file; or a radius"
    )
    wall_thickness: float = Field(
        0.01,
        ge=1e-4,
        le=1,
        description="wall thickness, m, in [1e-4, 1]; thick walls stop tunnelling",
    )
    material: str = Field("steel", description="name of a [materials] entry")

    @model_validator(mode="after")
    def _one_outline(self) -> Chamber:
        if (self.radius is None) == (self.shape is None):
            raise ValueError("give exactly one of radius (a round wall, m) or shape (a file)")
        return self


class FloorFriction(Strict):
    """[effects.floor_friction]: Coulomb friction of the floor under a horizontal rotor."""

    floor: Literal["corotating", "stationary"] = Field(
        "stationary", description="'corotating' (the rotor disc) or 'stationary' (chamber floor)"
    )
    friction: float = Field(ge=0, le=2, description="floor friction coefficient, in [0, 2]")


class AirDrag(Strict):
    """[effects.air_drag]: quadratic drag F = ½ ρ C_d A v² on each granule."""

    air_density: float = Field(
        1.204, ge=1e-3, le=10, description="air density, kg/m³, in [1e-3, 10]"
    )
    drag_coefficient: float = Field(0.47, ge=1e-3, le=5, description="C_d, in [1e-3, 5]")


class NoParameters(Strict):
    """An effect that takes no parameters: an empty table switches it on."""


class Effects(Strict):
    """[effects.NAME]: the effects this scene calls for. An effect not listed costs nothing."""

    floor_friction: FloorFriction | None = None
    gravity_in_plane: NoParameters | None = Field(
        None, description="gravity in the plane of a vertical rotor"
    )
    granule_collisions: NoParameters | None = Field(
        None, description="granules collide with each other"
    )
    hinge_friction: NoParameters | None = Field(
        None, description="apply hammers.hinge_friction at the hinges"
    )
    air_drag: AirDrag | None = None
    rotor_inertia: NoParameters | None = Field(
        None, description="the rotor has rotor.inertia and a drive limited to rotor.torque_limit"
    )

    @property
    def enabled(self) -> list[str]:
        """Names of the effects listed in the case."""
        return [name for name in type(self).model_fields if getattr(self, name) is not None]


class Solver(Strict):
    """[solver]: time stepping."""

    dt: float | Literal["auto"] = Field(
        "auto",
        description="time step, s, in [1e-12, 0.01], or 'auto' (from contact duration, tunnelling "
        "and rotor turn); with soft contacts the granules' step",
    )
    substeps: int = Field(
        1,
        ge=1,
        le=1000,
        description="rigid contacts: Pymunk steps per time step dt (each of dt/substeps), in "
        "[1, 1000]; soft contacts: 1 (see contact_model.granule_substeps)",
    )
    iterations: int = Field(10, ge=1, le=1000, description="Chipmunk solver iterations")
    duration: float = Field(
        0.1, ge=1e-6, le=LONGEST, description="simulated time, s, in [1e-6, 3600]"
    )
    seed: int = Field(0, ge=0, description="seed for anything random in the run, >= 0")
    ledger_tolerance: float = Field(
        0.01,
        ge=1e-6,
        le=1.0,
        description="the largest |closure| of the energy ledger at the end (its residual over "
        "the energy in play, a fraction: 0.01 is 1 %) with which a run counts as completed, "
        "in [1e-6, 1]; beyond it the run ends 'completed, ledger off' with exit status 3 "
        "(perga.machine.energy)",
    )
    threads: int | Literal["auto"] = Field(
        "auto",
        description="threads of the soft contact kernel, in [1, 256]: its pair forces are "
        "summed in this many chunks, which fix the results, computed by as many threads as "
        "cores are free; 'auto': one chunk below 4,000 granules, two from there (rigid "
        "contacts: one thread)",
    )

    @model_validator(mode="after")
    def _dt_range(self) -> Solver:
        if self.threads != "auto" and not 1 <= self.threads <= 256:
            raise ValueError(f"solver.threads must be in [1, 256] or 'auto' (got {self.threads})")
        if self.dt != "auto" and not FINEST_STEP <= self.dt <= 0.01:
            raise ValueError(f"solver.dt must be in [1e-12, 0.01] s or 'auto' (got {self.dt})")
        return self


def one_of(values: Iterable[str]) -> str:
    """The values quoted and listed as pydantic lists a Literal's: "'a', 'b' or 'c'"."""
    quoted = [f"'{v}'" for v in values]
    return quoted[0] if len(quoted) == 1 else f"{', '.join(quoted[:-1])} or {quoted[-1]}"


class ContactKind:
    """The type of ``contact_model.kind``: 'rigid' or a contact law's name, read from the
    registry (:data:`perga.contact.laws.LAWS`) whenever a case is validated or its schema
    written, so that every registered law is a kind."""

    @staticmethod
    def choices() -> tuple[str, ...]:
        """'rigid', then the registered laws."""
        return ("rigid", *LAWS)

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> core_schema.CoreSchema:
        return core_schema.no_info_plain_validator_function(self.validate)

    def __get_pydantic_json_schema__(self, schema: Any, handler: Any) -> dict[str, Any]:
        return {"enum": list(self.choices()), "type": "string"}

    def validate(self, value: object) -> str:
        """``value`` if it is a kind, else pydantic's error for a Literal of the kinds."""
        if isinstance(value, str) and value in self.choices():
            return value
        raise PydanticCustomError(
            "literal_error", "Input should be {expected}", {"expected": one_of(self.choices())}
        )


class ContactModelTable(Strict):
    """[contact_model]: how granule contacts are resolved.

    'rigid': Pymunk impulses (instantaneous, restitution and friction exact per impact);
    'linear' or 'hertz': soft spring-dashpot contacts of finite duration integrated by perga's
    kernel (:mod:`perga.contact.soft`), damping tuned to each pair's restitution, Cundall-Strack
    tangential spring capped by the pair's friction.
    """

    kind: Annotated[str, ContactKind()] = Field(
        "rigid", description="'rigid' (Pymunk impulses), 'linear' or 'hertz' (soft contacts)"
    )
    duration: float | None = Field(
        None,
        ge=1e-9,
        le=0.01,
        description="contact duration t_c of a granule striking a rigid wall head-on with "
        "the granule-hammer restitution, s, in [1e-9, 0.01] (hertz: at the fastest relative "
        "speed, where contacts are shortest); sets k_n (or give stiffness)",
    )
    stiffness: float | None = Field(
        None,
        ge=1,
        description="normal stiffness k_n, >= 1: N/m (linear; or duration) or (4/3)E*, Pa, "
        "shared by every pair (hertz: the contact stiffness is k_n·√R*; or give the materials' "
        "youngs_modulus and poisson_ratio)",
    )
    tangential_ratio: float | Literal["mindlin"] | None = Field(
        None,
        description="k_t/k_n of every pair: a number, in [0, 4/3] (linear: an elastic solid's "
        "2(1 − ν)/(2 − ν), 4/3 as ν → −1) or [0, 2] (hertz, on the secant k_n√(R*δ): "
        "3(1 − ν)/(2 − ν), 2 as ν → −1), or 'mindlin' (hertz: each pair's 6G*/E* from its "
        "materials' youngs_modulus and poisson_ratio, Mindlin 1949); default 'mindlin' for a "
        "hertz pair whose stiffness comes from its materials, else 2/7 (as LAMMPS)",
    )
    tangential_damping: float = Field(
        0.0,
        ge=0,
        lt=1,
        description="tangential damping ratio ζ_t, in [0, 1): a dashpot −2ζ_t√(k_t m_eff)·v_t "
        "beside the tangential spring of every soft contact (a sticking contact's tangential "
        "oscillation decays at ζ_t√(m_eff/m_t) of critical, m_t the contact's tangential "
        "effective mass: √3 ζ_t for a disc at a wall); default 0",
    )
    rolling: float = Field(
        0.0, ge=0, le=1, description="rolling-resistance coefficient μ_r, in [0, 1]"
    )
    end: Literal["force", "overlap"] = Field(
        "force",
        description="contact ends when the force returns to zero ('force', e > e⁻² ≈ 0.135) "
        "or when the overlap does ('overlap', attractive force allowed; any e > 0)",
    )
    steps_per_contact: float = Field(
        50.0,
        ge=10,
        le=1000,
        description="automatic step: t_c/steps_per_contact, in [10, 1000]; a heavily damped "
        "contact takes more, in proportion to its damping (at 50: 20 per dashpot time, e = "
        "0.05 takes 120)",
    )
    granule_substeps: int = Field(
        1,
        ge=1,
        le=100,
        description="soft granule steps per Pymunk step of the rotor and hammers, in [1, 100]",
    )

    @model_validator(mode="after")
    def _stiffness_given(self) -> ContactModelTable:
        if self.kind == "rigid":
            soft_only = sorted(self.model_fields_set - {"kind"})
            if soft_only:
                raise ValueError(
                    f"{', '.join(soft_only)}: for kind = {one_of(LAWS)} (soft contacts); "
                    "rigid contacts take none"
                )
            return self
        law, kind = self.law, self.kind
        if not law.from_materials and (self.duration is None) == (self.stiffness is None):
            raise ValueError(
                f"kind = '{kind}' needs exactly one of duration (s) or stiffness "
                f"({law.stiffness_unit})"
            )
        if law.from_materials and self.duration is not None and self.stiffness is not None:
            raise ValueError(
                f"kind = '{kind}' takes one of stiffness ({law.stiffness_unit}), duration (s) or "
                "the materials' youngs_modulus and poisson_ratio"
            )
        ratio = self.tangential_ratio
        if ratio == "mindlin" and not law.mindlin:
            mindlin = [name for name in LAWS if contact_law(name).mindlin]
            raise ValueError(f"tangential_ratio: 'mindlin' is for kind = {one_of(mindlin)}")
        if isinstance(ratio, float) and not 0.0 <= ratio <= law.max_tangential_ratio:
            raise ValueError(
                f"tangential_ratio: {ratio} is outside [0, {law.max_tangential_ratio:.4g}] for "
                f"kind = '{kind}' (an elastic solid's k_t/k_n, {law.ratio_limit})"
            )
        return self

    @property
    def soft(self) -> bool:
        """Whether granule contacts are soft (perga's kernel) rather than Pymunk impulses."""
        return self.kind != "rigid"

    @property
    def law(self) -> ContactLaw:
        """The soft contacts' law (:mod:`perga.contact.laws`; ValueError for 'rigid')."""
        return contact_law(self.kind)


class Output(Strict):
    """[output]: what to record and how often."""

    directory: str = Field("runs/{case}", description="output directory; {case} = file stem")
    every: float = Field(
        1e-3,
        ge=1e-7,
        le=LONGEST,
        description="recording interval of the tables in simulated time, s, in [1e-7, 3600]",
    )
    vtk_every: float | None = Field(
        None,
        ge=1e-7,
        le=LONGEST,
        description="recording interval of the ParaView series ('vtk') in simulated time, s, "
        "in [1e-7, 3600]; default: every (ParaView frames cost far more than table rows: a coarser "
        "interval makes a run with 'vtk' cheaper)",
    )
    record: tuple[
        Literal["granules", "hammers", "impacts", "energy", "releases", "outflow", "vtk"], ...
    ] = Field(
        ("granules", "hammers", "impacts", "energy", "vtk"),
        description="what to write, each named once: CSV tables (granules, hammers, impacts: "
        "impacts.csv and contacts.csv, each granule-hammer contact from start to end, energy, "
        "releases: granules pulled from their cells, outflow: granules gone through the "
        "outlet) and 'vtk' (ParaView .pvd series in RUN/vtk/, see perga.output.vtk)",
    )
    granule_table: Literal["csv", "parquet"] = Field(
        "csv",
        description="format of the granule table: 'csv' (granules.csv) or 'parquet' (the "
        "Parquet dataset granules.parquet/, one part per 2^20 rows, for large runs: smaller, "
        "faster to write and to read (docs/dev/performance.md); parts are written when "
        "full and at the end, so a killed run loses the part in memory; perga.output.tables)",
    )
    tables: Literal["csv", "parquet"] = Field(
        "csv",
        description="form of the tables once the run is complete: 'csv', or 'parquet' (each "
        "table written at the end as NAME.parquet, one zstd-compressed file, and its CSV "
        "removed; smaller, typed, the CSV's values exactly). While the run goes, and in a run "
        "that stopped before its end (which perga run --resume completes), the tables are "
        "CSV; every reader of a run takes either (perga.output.tables)",
    )
    checkpoint_every: float = Field(
        0.1,
        ge=0.0,
        le=LONGEST,
        description="simulated time between checkpoints, s, 0 (none) or in [1e-4, 3600]: the "
        "whole state in RUN/checkpoints/ (the last two kept), from which perga run --resume RUN "
        "goes on after a stop or a crash, bit for bit as if never stopped. A rigid run goes on "
        "from each checkpoint as a resumed one does, so this grid is part of its results "
        "(perga.run.checkpoints)",
    )
    checkpoint_wall: float = Field(
        0.0,
        ge=0.0,
        le=1e7,
        description="wall-clock time, s, 0 to 1e7, that must pass between checkpoint files: a "
        "checkpoint falling sooner is taken (and gone on from) but not written (0: every one)",
    )
    vtk_3d: bool = Field(
        False,
        description="with 'vtk': also the 3-D view, RUN/vtk/hammers3d.pvd, rotor3d.pvd and "
        "chamber3d.vtu: hammers and rotor disc extruded to their thickness, m (hammers: the "
        "plate's or the geometry's; rotor: its mesh's height, else the hammers'), centred on the "
        "rotor plane z = 0, and the chamber wall as tall as the tallest part (see "
        "perga.output.vtk3d)",
    )

    @model_validator(mode="after")
    def _checkpoints_not_too_often(self) -> Output:
        if 0 < self.checkpoint_every < 1e-4:
            raise ValueError(
                f"checkpoint_every = {self.checkpoint_every} s: 0 (no checkpoints) or >= 1e-4 s"
            )
        return self

    @field_validator("record")
    @classmethod
    def _each_once(cls, record: tuple[str, ...]) -> tuple[str, ...]:
        twice = sorted(name for name, n in Counter(record).items() if n > 1)
        if twice:
            raise ValueError(f"name each once ({', '.join(twice)} more than once)")
        return record

    @model_validator(mode="after")
    def _vtk_3d_needs_vtk(self) -> Output:
        if self.vtk_3d and "vtk" not in self.record:
            raise ValueError("vtk_3d = true needs 'vtk' in record")
        return self


class Region(Strict):
    """A rectangle: ``centre`` (m), ``size`` (width, height, m), turned by ``angle`` (rad)."""

    centre: tuple[float, float] = Field(description="centre of the rectangle, m")
    size: tuple[float, float] = Field(description="width and height, m, each > 0")
    angle: float = Field(0.0, description="turn of the rectangle, rad (width along +x at 0)")

    @model_validator(mode="after")
    def _positive(self) -> Region:
        if not (self.size[0] > 0 and self.size[1] > 0):
            raise ValueError(f"size must be two lengths > 0 m (got {list(self.size)})")
        return self


class Feed(Strict):
    """[feed]: granules inserted over time into ``region`` (each where it overlaps nothing:
    granules, hammers, the wall), free (kind "granules") or as comb pieces (kind "comb", the
    shape of ``granules.placement``, a comb, whose cells hold their granules)."""

    kind: Literal["granules", "comb"] = Field(
        "granules", description="free granules or comb pieces"
    )
    rate: float = Field(ge=1e-6, le=1e7, description="granules (or pieces) per s, or kg/s by mass")
    basis: Literal["number", "mass"] = Field("number", description="rate of number or of mass")
    start: float = Field(0.0, ge=0, description="first insertion, s")
    stop: float | None = Field(None, ge=1e-6, description="no insertion after, s; default: never")
    total: int | None = Field(None, ge=1, le=10_000_000, description="granules (pieces) in all")
    region: Region = Field(description="where they are put")
    velocity: tuple[float, float] = Field((0.0, 0.0), description="their velocity, m/s")


class Outlet(Strict):
    """[outlet]: where granules leave the chamber (are counted and taken out). ``radius``:
    farther than ``radius`` from the axis; ``line``: past the line through ``point`` whose
    ``normal`` points out; ``screen``: the line's segment of ``width`` about ``point``, passed
    only by granules narrower than ``aperture``."""

    kind: Literal["radius", "line", "screen"]
    radius: float | None = Field(None, ge=1e-3, le=5, description="radius kind, m")
    point: tuple[float, float] | None = Field(None, description="line, screen: a point on it, m")
    normal: tuple[float, float] | None = Field(None, description="line, screen: outward normal")
    width: float | None = Field(None, ge=1e-4, le=10, description="screen: its width, m")
    aperture: float | None = Field(None, ge=1e-5, le=0.1, description="screen: mesh opening, m")

    @model_validator(mode="after")
    def _parameters(self) -> Outlet:
        need = {
            "radius": ("radius",),
            "line": ("point", "normal"),
            "screen": ("point", "normal", "width", "aperture"),
        }[self.kind]
        missing = [n for n in need if getattr(self, n) is None]
        if missing:
            raise ValueError(f"kind '{self.kind}' needs {', '.join(missing)}")
        if self.normal is not None and math.hypot(*self.normal) == 0:
            raise ValueError("normal must not be (0, 0)")
        return self


class Damage(Strict):
    """[damage]: each granule-hammer impact may break the granule (its material's
    ``breakage``); broken granules are marked, or taken out. Whether one breaks is drawn with
    the impact's breakage probability (seeded by ``solver.seed``); its expected survival is
    recorded either way."""

    action: Literal["mark", "remove"] = Field("mark", description="what happens to a broken one")


class Case(Strict):
    """A perga case file."""

    title: str = Field("", description="one-line title")
    description: str = Field("", description="free text: what the case is for")
    rotor: Rotor
    hammers: Hammers
    granules: Granules
    materials: dict[str, Material] = Field(description="materials by name: [materials.NAME]")
    contacts: list[ContactPair] = Field(min_length=1)
    chamber: Chamber | None = Field(None, description="the wall (needed by perga run)")
    feed: Feed | None = Field(None, description="granules inserted over time")
    outlet: Outlet | None = Field(None, description="where granules leave")
    damage: Damage | None = Field(None, description="breakage of granules by impacts")
    effects: Effects = Field(default_factory=Effects)
    contact_model: ContactModelTable = Field(default_factory=ContactModelTable)
    solver: Solver = Field(default_factory=Solver)
    output: Output = Field(default_factory=Output)
    gravity: float = Field(9.80665, ge=0, le=100, description="gravity, m/s², in [0, 100]")
    paper: PaperStudy | None = Field(None, description="inputs of perga paper-check")
    _source_dir: Path | None = PrivateAttr(None)
    _data: dict | None = PrivateAttr(None)
    _overrides: tuple[str, ...] = PrivateAttr(())
    _path: Path | None = PrivateAttr(None)

    def attach_source(
        self,
        folder: Path | None,
        data: dict | None,
        overrides: tuple[str, ...] = (),
        path: Path | None = None,
    ) -> None:
        """Record where the case came from: its file's folder, the TOML data it was validated
        from, the overrides applied to it and the file as named."""
        self._source_dir, self._data, self._overrides = folder, data, overrides
        self._path = path

    @property
    def source_path(self) -> Path | None:
        """The case file as it was named when loaded (problems name it), or None."""
        return self._path

    @property
    def source_data(self) -> dict | None:
        """The TOML data the case was validated from, overrides applied (None if built in
        Python)."""
        return self._data

    @property
    def overrides(self) -> tuple[str, ...]:
        """The ``KEY=VALUE`` overrides applied to the file, in order."""
        return self._overrides

    @property
    def source_dir(self) -> Path | None:
        """The folder of the case file it was loaded from (relative geometry paths start
        there), or None."""
        return self._source_dir

    def contact(self, a: str, b: str) -> ContactPair:
        """The [[contacts]] entry of materials a and b (KeyError if there is none)."""
        for pair in self.contacts:
            if sorted(pair.pair) == sorted((a, b)):
                return pair
        raise KeyError(f"no [[contacts]] entry for the pair ({a}, {b})")

    @property
    def granule_hammer_contact(self) -> ContactPair:
        """The contact between the granule and hammer materials."""
        return self.contact(self.granules.material, self.hammers.material)

    @property
    def granule_density(self) -> float:
        """Density of the granules' material, kg/m³."""
        return self.materials[self.granules.material].density

    @property
    def granule_mass(self) -> float:
        """Mass of one granule, kg: given, or density·πr²·thickness."""
        g = self.granules
        return (
            g.mass
            if g.mass is not None
            else self.granule_density * math.pi * g.radius**2 * g.thickness
        )

    @property
    def granule_thickness(self) -> float:
        """Out-of-plane length of one granule, m: given, or mass/(density·πr²)."""
        g = self.granules
        return (
            g.thickness
            if g.thickness is not None
            else g.mass / (self.granule_density * math.pi * g.radius**2)
        )

    @property
    def hammer_plate(self) -> PlateHammer:
        """The hammer as a plate of its material's density (plate shapes only: see
        :func:`perga.model.hammer_geometry.hammer_geometry` for any shape)."""
        if not isinstance(self.hammers.shape, PlateShape):
            raise ValueError("hammers.shape: a plate is needed here (kind = 'plate')")
        return self.hammers.plate(self.materials[self.hammers.material].density)
