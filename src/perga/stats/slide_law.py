"""Every slide of a run's granules along a hammer face against the model of a disc that slips
and rolls on a face turning with the rotor (:mod:`perga.analytic.disc_on_face`; a granule that
does not roll: the sliding point of :class:`~perga.analytic.sliding.BladeSlide`), started from
the slide's first recorded state (contacts.csv, :class:`~perga.model.records.Contact`).

A **slide** is a granule-hammer contact that lasts longer than a contact time: at least
:data:`SLIDE_STEPS` machine steps for rigid contacts (an impact is one or two), at least
:data:`SLIDE_CONTACT_TIMES` normal-impact durations for soft ones. Its face frame is taken at
its start: x along the face, outward, from the foot of the perpendicular from the axis; +y the
direction of rotation; the granule's centre at y = h; the face leading when the hammer's
normal points along +y. The model turns that frame with the rotor for the slide's duration T
and is compared at its end: the granule's velocity (fixed frame), its position along the face,
its spin and its speed.

A slide is in the model's regime (**on a face turning with the rotor**) when nothing else
touches the granule (contacts.csv's ``other_contacts`` 0), it is not held in a cell, and its
hammer turned with the rotor: |θ_hammer − ωT| ≤ :data:`TURN_TOLERANCE`·ωT. A hinged hammer
that swings while a granule slides on it is a face the model does not have; such slides are
compared and reported as that regime, with the hammer's lag.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from perga.analytic.disc_on_face import DiscOnFace
from perga.analytic.sliding import BladeSlide, Face, FloorMode
from perga.stats.episodes import in_words, median_and_largest
from perga.stats.tables import Run

ON_FACE = "on a face turning with the rotor"
SLIDE_STEPS = 10
"""Machine steps a rigid contact lasts at least to be a slide."""
SLIDE_CONTACT_TIMES = 3.0
"""Normal-impact durations t_c a soft contact lasts at least to be a slide."""
TURN_TOLERANCE = 0.01
"""The hammer's turn over a slide may differ from the rotor's ωT by this fraction of ωT."""


@dataclass(frozen=True)
class SlideCheck:
    """One slide, simulated against the model at its end (SI; errors dimensionless)."""

    index: int
    """Row of contacts.csv."""
    start: float
    duration: float
    granule: int
    hammer: int
    regime: str
    """``ON_FACE``, or why the model cannot describe this slide."""
    face: str
    """"leading" or "trailing"."""
    hammer_lag: float
    """θ_hammer − ωT over the slide, rad (0: it turned with the rotor)."""
    velocity_error: float
    """|v_sim − v_model| / |v_model|: the granule's velocity at the end, fixed frame (as an
    impact's velocity after is compared)."""
    position_error: float
    """|x_sim − x_model| / |x_model − x0|: its position along the face at the end, over the
    model's travel."""
    spin_error: float
    """|Ω_sim − Ω_model|·a / |v_model|: the spin at the end as a rim speed."""
    exit_speed: tuple[float, float]
    """The speed of the granule's centre in the fixed frame at the end, m/s, simulated and
    model."""
    travel: float
    """x_model − x0, m: how far the model's granule moves along the face."""
    rolled: float
    """The share of the slide the model's disc rolls (0 for a sliding point)."""
    model_event: str
    """How the model's slide ended: "end" (it lasted T), "stuck" (a sliding point held by
    static friction), or "separated" (it left the face earlier: the end is not compared)."""


def _unavailable(run: Run) -> str | None:
    """Why no slide of ``run`` can be predicted, or None."""
    if not run.contacts:
        if run.impacts and run.impacts["time"].size:
            return "the run has impacts but no contacts.csv (an older run)"
        return "no granule-hammer contact was recorded"
    if run.case.rotor.inertia is not None:
        return "a driven rotor of finite inertia (the model takes the rotor's speed as given)"
    if run.case.effects.gravity_in_plane is not None:
        return "gravity in the plane of a vertical rotor (the model has the floor's only)"
    return None


def contact_time(run: Run) -> float:
    """The contact time a slide outlasts, s: :data:`SLIDE_STEPS` machine steps (rigid) or
    :data:`SLIDE_CONTACT_TIMES` normal-impact durations of the granule-hammer pair (soft)."""
    plan = run.summary.get("time_step") or {}
    if plan.get("contact_duration"):
        return SLIDE_CONTACT_TIMES * float(plan["contact_duration"])
    return SLIDE_STEPS * float(plan.get("machine") or run.summary["dt"])


def slides(run: Run) -> np.ndarray:
    """Rows of contacts.csv that are slides (module docstring)."""
    c = run.contacts
    return np.flatnonzero(c["end"] - c["start"] >= contact_time(run) * (1 - 1e-9))


def _floor(run: Run) -> tuple[FloorMode, float]:
    floor = run.case.effects.floor_friction
    return ("none", 0.0) if floor is None else (floor.floor, floor.friction)


def _regime(row: dict[str, float], lag: float, turn: float) -> str:
    if row["held"]:
        return "the granule is held in the comb"
    if row["other_contacts"] > 0:
        count = int(row["other_contacts"])
        return f"{count} other contact{'s' if count > 1 else ''} during the slide"
    if abs(lag) > TURN_TOLERANCE * abs(turn):
        return "the hammer swings while the granule slides"
    return ON_FACE


def _rotate(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


@dataclass(frozen=True)
class _Frame:
    """A slide's face frame at its start (module docstring): unit vectors along the face
    (outward) and across it (+y, the direction of rotation), the granule's x0 and h (m), its
    velocity along the face relative to it u0 (m/s) and the face's side."""

    along: np.ndarray
    across: np.ndarray
    x0: float
    h: float
    u0: float
    face: Face

    @classmethod
    def at_start(cls, row: dict[str, float], w: float) -> _Frame:
        p0 = np.array([row["x_start"], row["y_start"]])
        n = np.array([row["nx"], row["ny"]])
        along = np.array([n[1], -n[0]])
        if along @ p0 < 0:
            along = -along
        across = np.array([-along[1], along[0]])
        relative = np.array([row["vx_start"], row["vy_start"]]) - w * np.array([-p0[1], p0[0]])
        face: Face = "leading" if n @ across > 0 else "trailing"
        return cls(along, across, float(p0 @ along), float(p0 @ across),
                   float(relative @ along), face)  # fmt: skip

    def along_at_end(self, row: dict[str, float], w: float, T: float) -> float:
        """The simulated end's x (m) in this frame turned with the rotor through ωT."""
        return float(_rotate(np.array([row["x_end"], row["y_end"]]), -w * T) @ self.along)

    def fixed_velocity(self, x: float, u: float, w: float, T: float) -> np.ndarray:
        """The fixed-frame velocity (m/s) of a granule at x on the face's line, moving along it
        at u, after the face turned through ωT."""
        p = x * self.along + self.h * self.across
        return _rotate(u * self.along + w * np.array([-p[1], p[0]]), w * T)


def check_slides(run: Run) -> list[SlideCheck]:
    """Every slide of ``run`` against the model; ValueError (its reason) where none can be
    predicted."""
    if reason := _unavailable(run):
        raise ValueError(f"{run.name}: {reason}")
    w = run.omega  # > 0: rotors turn counter-clockwise
    friction = run.case.granule_hammer_contact.friction
    floor, floor_friction = _floor(run)
    radius = dict(zip(run.granules["id"].astype(int), run.granules["radius"], strict=True))
    rolls = run.case.granules.rolls
    checks = []
    for i in slides(run):
        row = {k: float(v[i]) for k, v in run.contacts.items()}
        a = float(radius[int(row["granule"])])
        T = row["end"] - row["start"]
        frame = _Frame.at_start(row, w)
        slide = BladeSlide(w, friction, floor_friction, floor, frame.face, offset=frame.h,
                           gravity=run.case.gravity, inner=-math.inf)  # fmt: skip
        if rolls:
            disc = DiscOnFace(slide, a).integrate(frame.x0, frame.u0, row["spin_start"], T)
            x_m, u_m, spin_m, event = disc.x[-1], disc.v[-1], disc.spin[-1], disc.event
            rolled, left = _rolled_share(disc.t, disc.rolling), disc.t[-1]
        else:
            point = slide.integrate(frame.x0, frame.u0, T)
            x_m, u_m, spin_m, event, rolled = point.x[-1], point.v[-1], 0.0, point.event, 0.0
            left = point.t[-1]
        x1 = frame.along_at_end(row, w, T)
        v_law = frame.fixed_velocity(x_m, u_m, w, T)
        v_sim = np.array([row["vx_end"], row["vy_end"]])
        speed = float(np.hypot(*v_law))
        lag = row["hammer_turn"] - w * T
        stays = event != "separated"
        regime = _regime(row, lag, w * T) if stays else (
            "the model's granule leaves the face (N < 0)"
            + (f" after {left * 1e3:.3g} ms" if left > 0 else " at once"))  # fmt: skip
        checks.append(
            SlideCheck(
                index=int(i),
                start=row["start"],
                duration=T,
                granule=int(row["granule"]),
                hammer=int(row["hammer"]),
                regime=regime,
                face=frame.face,
                hammer_lag=lag,
                velocity_error=float(np.hypot(*(v_sim - v_law))) / speed if stays else math.nan,
                position_error=abs(x1 - x_m) / max(abs(x_m - frame.x0), a)
                if stays else math.nan,
                spin_error=abs(row["spin_end"] - spin_m) * a / speed
                if stays and rolls else math.nan,
                exit_speed=(float(np.hypot(*v_sim)), speed),
                travel=float(x_m - frame.x0),
                rolled=rolled,
                model_event=event,
            )
        )  # fmt: skip
    return checks


def _rolled_share(t: np.ndarray, rolling: np.ndarray) -> float:
    """The share of the time ``t`` (s) spent where ``rolling`` (each interval by its end)."""
    span = t[-1] - t[0]
    return float(np.sum(np.diff(t) * rolling[1:]) / span) if span > 0 else 0.0


@dataclass(frozen=True)
class SlideSummary:
    """A run's checked slides taken together (:func:`summarise_slides`)."""

    checks: list[SlideCheck]
    on_face: list[SlideCheck]
    """The slides in the model's regime whose end the model reaches."""
    regimes: Counter[str] = field(default_factory=Counter)
    """How many slides are in each regime but ``ON_FACE``."""

    @property
    def others(self) -> str:
        """The regimes but ``ON_FACE`` in words, most frequent first."""
        return in_words(self.regimes)

    def worst(self, count: int) -> list[SlideCheck]:
        """The ``count`` compared slides with the largest velocity errors, largest first."""
        compared = [c for c in self.checks if math.isfinite(c.velocity_error)]
        return sorted(compared, key=lambda c: -c.velocity_error)[:count]

    def statistics(self, checks: list[SlideCheck] | None = None) -> dict[str, dict[str, float]]:
        """Median and largest error of each statistic over ``checks`` (default: the slides on
        a face turning with the rotor)."""
        chosen = self.on_face if checks is None else checks
        return median_and_largest(
            {
                "velocity at the end (over its speed)": [c.velocity_error for c in chosen],
                "position along the face (over the travel)": [c.position_error for c in chosen],
                "spin at the end (rim speed, over the velocity)": [c.spin_error for c in chosen],
                "speed at the end (relative)": [
                    abs(c.exit_speed[0] / c.exit_speed[1] - 1) for c in chosen
                ],
            }
        )


def summarise_slides(checks: list[SlideCheck]) -> SlideSummary:
    """``checks`` taken together: those on a face turning with the rotor and compared, the
    other regimes."""
    on_face = [c for c in checks if c.regime == ON_FACE and math.isfinite(c.velocity_error)]
    regimes = Counter(c.regime for c in checks if c.regime != ON_FACE)
    return SlideSummary(checks, on_face, regimes)
