"""The scenes of ``perga accuracy`` as case files, and their independent references (SI units).

Every scene is a validated :class:`~perga.case.Case` (schema and cross-checks, as ``perga run``
loads it) built from a dict, with the contact model and time-step settings of one
:class:`Setting` put into ``[contact_model]`` and ``[solver]``. One granule (r = 2 mm,
m = 100 mg, a disc) and steel plate hammers; friction 0 wherever a closed form assumes it.

Scenes and what each measures (the error definitions are in :mod:`perga.studies.accuracy`):

* ``restitution``: a granule flies head-on at 2 m/s onto the flat face of a welded plate on a
  rotor at rest (ω = 1e-6 rad/s, the schema's floor), e = 0.7: the rebound speed over
  the approach speed against e.
* ``blade``: a granule slides out along the frictionless face of a welded blade at ω = 100 rad/s
  (tests/cases/closed-form/blade-frictionless.toml): the exit speed relative to the blade against
  :func:`perga.analytic.sliding.frictionless_exit`.
* ``hinged``: a hinged plate hammer (78 g, ω = 100 rad/s, tests/cases/closed-form/
  hinged-impact.toml with a 1 mm gap) strikes a granule at rest: the granule's velocity after
  the impact against :func:`perga.analytic.impact.hinged_impact` evaluated at the exact contact
  pose (the hammer co-rotating at α = 0, so the pose follows from geometry alone); the same run
  gives the energy ledger's closure.
* ``bounce``: a granule dropped 5 mm onto a horizontal welded plate (vertical rotor at rest,
  in-plane gravity), e = 0.8, four impacts: the height y(t) against the model's own exact
  solution (rigid: parabolas and Newton's restitution; soft: parabolas and each contact's
  force law integrated by solve_ivp, DOP853, rtol 1e-12).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from scipy.integrate import solve_ivp

from perga.analytic.contact import HERTZ_DURATION_COEFFICIENT
from perga.analytic.impact import hinged_impact
from perga.analytic.sliding import frictionless_exit
from perga.case import Case, CaseError
from perga.contact.laws import contact_law
from perga.model.compile import compile_case
from perga.model.plan import pair_stiffness
from perga.model.system import System

Model = Literal["rigid", "linear", "hertz"]

RADIUS = 0.002
"""Granule radius, m."""
MASS = 1e-4
"""Granule mass, kg."""


@dataclass(frozen=True)
class Setting:
    """One point of the settings grid.

    model: contact model; dt: rigid time step, s (None for soft: t_c/steps_per_contact);
    iterations: Chipmunk solver iterations; steps_per_contact: soft steps per contact duration;
    granule_substeps: soft granule steps per Pymunk step; contact_duration: soft contacts' head-on
    duration t_c, s (linear: contact_model.duration; Hertz: the stiffness giving t_c undamped at
    the scene's impact speed).
    """

    model: Model
    dt: float | None = None
    iterations: int = 10
    steps_per_contact: float = 50.0
    granule_substeps: int = 1
    contact_duration: float = 1e-4

    @property
    def family(self) -> str:
        """The plot line this setting belongs to (what varies along it: dt or steps_per_contact)."""
        if self.model == "rigid":
            return f"rigid, {self.iterations} iterations"
        k = self.granule_substeps
        return f"{self.model} t_c={self.contact_duration:.0e} s, {k} substep{'s' * (k > 1)}"

    @property
    def label(self) -> str:
        """A compact name of the setting."""
        if self.model == "rigid":
            return f"rigid dt={self.dt:.0e} s it={self.iterations}"
        return (
            f"{self.model} t_c={self.contact_duration:.0e} s /{self.steps_per_contact:g} "
            f"k={self.granule_substeps}"
        )


def hertz_stiffness_for(duration: float, speed: float, m_eff: float = MASS) -> float:
    """contact_model.stiffness ((4/3)E*, Pa) giving an undamped Hertz contact of a granule on a
    flat partner the duration t_c (s) at impact speed v (m/s): k = k_n √r with
    t_c = C (m²/(k² v))^{1/5} (:data:`HERTZ_DURATION_COEFFICIENT`)."""
    k = m_eff / math.sqrt(speed * (duration / HERTZ_DURATION_COEFFICIENT) ** 5)
    return k / math.sqrt(RADIUS)


def _base(e: float, *, omega: float, hammers: dict[str, Any], chamber: float) -> dict[str, Any]:
    """The parts every scene shares: materials, the frictionless contact of restitution e."""
    return {
        "rotor": {"plane": "horizontal", "omega": omega, "radius": 0.15},
        "hammers": {"count": 1, "material": "steel", **hammers},
        "granules": {"count": 1, "radius": RADIUS, "mass": MASS, "material": "beebread"},
        "materials": {"beebread": {"density": 1400.0}, "steel": {"density": 7850.0}},
        "contacts": [{"pair": ["beebread", "steel"], "restitution": e, "friction": 0.0}],
        "chamber": {"radius": chamber, "material": "steel"},
        "output": {"record": ["impacts", "energy"]},
    }


def _placement(position: tuple[float, float], velocity: tuple[float, float]) -> dict[str, Any]:
    return {"kind": "explicit", "positions": [list(position)], "velocities": [list(velocity)]}


@dataclass(frozen=True)
class Scene:
    """A scene: its case without contact model and solver, the speed a Hertz contact is tuned
    at (m/s), and the simulated duration, s."""

    name: str
    data: dict[str, Any]
    hertz_speed: float
    duration: float

    def case(self, setting: Setting) -> tuple[Case, System]:
        """The validated case of this scene under ``setting`` and its system (CaseError, each
        problem naming the scene, if the cross-checks refuse it, e.g. a rigid step that lets the
        granule tunnel)."""
        data = copy.deepcopy(self.data)
        solver: dict[str, Any] = {"duration": self.duration, "iterations": setting.iterations}
        if setting.model == "rigid":
            solver["dt"] = setting.dt
            contact = {"kind": "rigid"}
        else:
            contact = {
                "kind": setting.model,
                "steps_per_contact": setting.steps_per_contact,
                "granule_substeps": setting.granule_substeps,
            }
            t_c = setting.contact_duration
            if contact_law(setting.model).fixed_duration:
                contact["duration"] = t_c
            else:
                contact["stiffness"] = hertz_stiffness_for(t_c, self.hertz_speed)
        data["solver"], data["contact_model"] = solver, contact
        case = Case.model_validate(data)
        try:
            return case, compile_case(case)
        except CaseError as exc:
            raise CaseError([f"{self.name}: {p}" for p in exc.problems]) from None


# --- restitution on a flat face -----------------------------------------------------------

FACE_WIDTH = 0.02
"""Width of the welded plates of the restitution and bounce scenes, m (face at y = width/2)."""


def _welded_plate(length: float) -> dict:
    """[hammers] of one 0.1 kg plate welded at the axis, ``length`` (m) along +x."""
    return {
        "mass": 0.1,
        "hinge_radius": 0.0,
        "mount": "welded",
        "shape": {"kind": "plate", "length": length, "width": FACE_WIDTH},
    }


def restitution_scene() -> Scene:
    """Head-on impact at 2 m/s on a welded plate's face, e = 0.7; touch after 0.5 ms."""
    speed, gap = 2.0, 1e-3
    data = _base(
        0.7,
        omega=1e-6,
        hammers=_welded_plate(0.1),
        chamber=0.2,
    )
    start = (0.05, FACE_WIDTH / 2 + RADIUS + gap)
    data["granules"]["placement"] = _placement(start, (0.0, -speed))
    return Scene("restitution", data, hertz_speed=speed, duration=1.5e-3)


# --- frictionless blade ---------------------------------------------------------------------

BLADE = {"omega": 100.0, "x0": 0.05, "v0": 0.5, "tip": 0.15, "width": 0.004}
"""The blade scene: ω (rad/s), start x0 (m) and speed v0 relative to the blade (m/s), tip (m),
blade width (m)."""


def blade_exit_reference() -> tuple[float, float]:
    """Exit time (s) and exit speed relative to the blade (m/s) of the blade scene."""
    b = BLADE
    return frictionless_exit(b["omega"], b["x0"], b["v0"], b["tip"])


def blade_scene() -> Scene:
    """A granule on the leading face of a welded blade (offset h = width/2 + r), sliding out
    from x0 at v0; runs 5 % past the exit time. e = 0.5 (a sustained contact: e does not enter
    the closed form; soft contacts need e > e⁻²)."""
    b = BLADE
    omega, h = b["omega"], b["width"] / 2 + RADIUS
    data = _base(
        0.5,
        omega=omega,
        hammers={
            "mass": 0.1,
            "hinge_radius": 0.0,
            "mount": "welded",
            "shape": {"kind": "plate", "length": b["tip"], "width": b["width"]},
        },
        chamber=0.25,
    )
    velocity = (b["v0"] - omega * h, omega * b["x0"])  # v_rel along x plus ω × r
    data["granules"]["placement"] = _placement((b["x0"], h), velocity)
    t_exit, v_exit = blade_exit_reference()
    return Scene("blade", data, hertz_speed=v_exit, duration=1.05 * t_exit)


# --- hinged hammer strikes a granule at rest -----------------------------------------------

HINGED = {"omega": 100.0, "R": 0.12, "a": 0.06, "gap": 1e-3}
"""ω (rad/s), hinge radius R (m), strike distance a (m), gap from the face to the granule (m)."""


def hinged_scene() -> Scene:
    """One hinged plate hammer (100 × 20 mm, 78 g, hinge 10 mm from its inner end) at α = 0
    strikes a granule at rest at x = R + a, `gap` ahead of the leading face; e = 0.6; 1 ms."""
    hs = HINGED
    data = _base(
        0.6,
        omega=hs["omega"],
        hammers={
            "mass": 0.078,
            "hinge_radius": hs["R"],
            "mount": "hinged",
            "shape": {
                "kind": "plate",
                "length": 0.1,
                "width": 0.02,
                "hinge_offset": 0.01,
                "strike_distance": hs["a"],
            },
        },
        chamber=0.25,
    )
    start = (hs["R"] + hs["a"], 0.01 + RADIUS + hs["gap"])
    data["granules"]["placement"] = _placement(start, (0.0, 0.0))
    speed = hs["omega"] * math.hypot(*start)
    return Scene("hinged", data, hertz_speed=speed, duration=1e-3)


def hinged_reference(case: Case) -> np.ndarray:
    """Granule velocity (m/s) after the instantaneous impact of the hinged scene.

    The hammer co-rotates with the rotor at α = 0 (Ω = ω, its equilibrium in the centrifugal
    field) until it touches the granule at rest at p; the leading face's normal at rotor angle θ
    is n = (−sin θ, cos θ), and touch means p·n = width/2 + r (the hinge lies on the axis line,
    so its term vanishes): θ = atan2(p_y, p_x) − asin((width/2 + r)/|p|). Then
    :func:`perga.analytic.impact.hinged_impact` with r_k = p − r n − hinge.
    """
    h, g = case.hammers, case.granules
    plate = case.hammer_plate
    omega = case.rotor.angular_velocity
    (p,) = np.array(g.placement.positions, dtype=float)
    reach = h.shape.width / 2 + g.radius
    theta = math.atan2(p[1], p[0]) - math.asin(reach / math.hypot(*p))
    axis = np.array([math.cos(theta), math.sin(theta)])
    n = np.array([-axis[1], axis[0]])
    hinge = h.hinge_radius * axis
    result = hinged_impact(
        M=h.mass,
        I_A=plate.inertia_about_hinge,
        r_c=plate.hinge_to_centre_of_mass * axis,
        r_k=p - g.radius * n - hinge,
        n=n,
        Omega=omega,
        v_A=omega * np.array([-hinge[1], hinge[0]]),
        m=case.granule_mass,
        v_g=(0.0, 0.0),
        e=case.granule_hammer_contact.restitution,
    )
    return np.asarray(result.granule_velocity, dtype=float)


# --- bouncing granule: successive impacts ----------------------------------------------------

BOUNCE = {"drop": 5e-3, "impacts": 4, "e": 0.8, "x": 0.1}
"""Drop height above the face (m), impacts before the run ends, restitution, x of the granule
(m)."""


def _bounce_surface() -> float:
    """Height of the granule's centre when it touches the face, m."""
    return FACE_WIDTH / 2 + RADIUS


def bounce_scene(gravity: float) -> Scene:
    """A granule dropped ``drop`` onto a horizontal welded plate (vertical rotor, gravity g in
    the plane); runs to the middle of the flight after the last counted impact."""
    data = _base(
        BOUNCE["e"],
        omega=1e-6,
        hammers=_welded_plate(0.2),
        chamber=0.25,
    )
    data["rotor"]["plane"] = "vertical"
    data["effects"] = {"gravity_in_plane": {}}
    data["gravity"] = gravity
    start = (BOUNCE["x"], _bounce_surface() + BOUNCE["drop"])
    data["granules"]["placement"] = _placement(start, (0.0, 0.0))
    v = math.sqrt(2 * gravity * BOUNCE["drop"])
    e, n = BOUNCE["e"], BOUNCE["impacts"]
    flights = sum(2 * v * e**k / gravity for k in range(1, n))
    duration = v / gravity + flights + v * e**n / gravity
    return Scene("bounce", data, hertz_speed=v, duration=duration)


ContactLaw = Callable[[float, float], float]
"""F(δ, δ̇): the normal force of a soft contact, N (clamped at 0)."""


def soft_contact_law(case: Case) -> ContactLaw:
    """The granule-on-welded-face law the case defines, in closed form (not the kernel's,
    :meth:`perga.contact.laws.base.ContactLaw.normal_force`): its own stiffness, m_eff = m (a
    welded hammer is immovable), the granule's radius, damping tuned to e under
    contact_model.end, clamped at F >= 0 when the contact ends at zero force."""
    cm = case.contact_model
    k_n = pair_stiffness(case, case.granules.material, case.hammers.material)
    e = case.granule_hammer_contact.restitution
    return cm.law.normal_force(k_n, e, case.granule_mass, case.granules.radius, cm.end)


@dataclass(frozen=True)
class Piece:
    """One piece of a bounce: a parabola (flight) or a dense solve_ivp solution (contact)."""

    t0: float
    t1: float
    y: Callable[[float], float]


def _parabola(t0: float, y0: float, v0: float, g: float, t1: float) -> Piece:
    return Piece(t0, t1, lambda t: y0 + v0 * (t - t0) - 0.5 * g * (t - t0) ** 2)


def _soft_contact(
    t0: float, v_in: float, g: float, m: float, law: ContactLaw, surface: float
) -> tuple[Piece, float]:
    """Contact from touch (δ = 0, approach speed v_in > 0) until the overlap is back to 0, under
    the clamped law and gravity, by solve_ivp (DOP853, rtol 1e-12); returns the piece and the
    upward speed at separation, m/s."""

    def rhs(_t: float, s: np.ndarray) -> list[float]:
        delta, rate = s
        return [rate, g - law(max(delta, 0.0), rate) / m]

    def apart(_t: float, s: np.ndarray) -> float:
        return s[0]

    apart.terminal, apart.direction = True, -1.0
    sol = solve_ivp(
        rhs,
        (0.0, 1.0),
        [0.0, v_in],
        method="DOP853",
        rtol=1e-12,
        atol=1e-16,
        events=apart,
        dense_output=True,
        first_step=1e-9,
    )
    if sol.status != 1:
        raise RuntimeError(f"bounce reference: the contact did not end ({sol.message})")
    t_end = float(sol.t_events[0][0])
    piece = Piece(t0, t0 + t_end, lambda t: surface - float(sol.sol(t - t0)[0]))
    return piece, -float(sol.y_events[0][0][1])


class BounceReference:
    """y(t) of the bounce scene, m: the model's own exact motion up to ``t_end``.

    Rigid: parabolas between impacts at the touching height, each impact reversing the speed
    times e. Soft: parabolas while apart, each contact integrated (:func:`_soft_contact`) with
    gravity acting throughout.
    """

    def __init__(self, case: Case, t_end: float) -> None:
        g = case.gravity
        surface = _bounce_surface()
        (start,) = case.granules.placement.positions
        law = None if case.contact_model.kind == "rigid" else soft_contact_law(case)
        e = case.granule_hammer_contact.restitution
        t, y, v = 0.0, float(start[1]), 0.0
        pieces: list[Piece] = []
        while t < t_end:
            # flight from (t, y, v) down to the surface
            root = v * v + 2 * g * (y - surface)
            t_touch = t + (v + math.sqrt(root)) / g
            pieces.append(_parabola(t, y, v, g, t_touch))
            v_in = math.sqrt(root)
            if law is None:
                t, y, v = t_touch, surface, e * v_in
            else:
                piece, v = _soft_contact(t_touch, v_in, g, case.granule_mass, law, surface)
                pieces.append(piece)
                t, y = piece.t1, surface
        self.pieces = pieces

    def height(self, t: float) -> float:
        """y(t), m."""
        for piece in self.pieces:
            if t <= piece.t1:
                return piece.y(t)
        raise ValueError(f"t = {t} s is past the reference")
