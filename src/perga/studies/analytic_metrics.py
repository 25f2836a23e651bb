"""The analytical counterparts of a calibration's metrics, the cheap level of a two-fidelity
calibration (:mod:`perga.studies.surrogate`).

* A shot (``granules.placement.kind = "shot"``) at an immovable face, its restitution e and
  friction f the pair's, gives by :func:`perga.analytic.impact.oblique_impact` (a disc, Brach
  2007, Stronge 2000) the normal restitution, the tangential restitution and the rebound angle
  at the centre and at the contact point (``shot_*``, ``first_impact_*``), in the conventions
  of :mod:`perga.stats.metrics`.
* A granule at rest struck by a hinged hammer (one granule placed explicitly) gives its speed
  after the first impact (``granule_speed_after_impact:1``): v' = (1 + e)·M/(M + m)·ωρ, the
  face meeting it head-on at ωρ (ρ its distance from the axis), M = I_A/d² the hammer's
  effective mass at the arm d = ρ − hinge radius (:func:`~perga.analytic.impact.
  hinged_effective_mass`, :func:`~perga.analytic.impact.normal_impact`).

The laws leave out what the simulation has and the surrogate's discrepancy learns: the face's
motion and mass (a hinged or turning hammer), the hammer's swing, friction on the floor, a
contact found a step deep, a soft contact's duration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from perga.analytic.impact import (
    ObliqueImpact,
    hinged_effective_mass,
    normal_impact,
    oblique_impact,
)
from perga.case.load import load_case
from perga.case.schema import Case, ExplicitPlacement, ShotPlacement
from perga.model.hammer_geometry import hammer_geometry
from perga.model.placement import shot, shot_face
from perga.stats.energy import rebound_angle
from perga.studies.jobs import toml_value

QUANTITIES = {
    "restitution": ("restitution", "centre"),
    "tangential_restitution_centre": ("beta", "centre"),
    "tangential_restitution_contact": ("beta", "contact"),
    "rebound_angle_centre": ("angle", "centre"),
    "rebound_angle_contact": ("angle", "contact"),
}
"""A rebound metric's name after ``shot_`` or ``first_impact_``: what it is, at which point."""


class NoAnalyticModelError(ValueError):
    """A metric, case or fitted key the analytical model does not cover; says which and why."""


STRUCK = "granule_speed_after_impact:1"
"""The metric of a granule at rest struck by a hinged hammer."""


def _quantity(metric: str) -> tuple[str, str, str]:
    """The scene a metric needs ("shot" or "struck"), what it is and at which point."""
    if metric == STRUCK:
        return "struck", "speed", "centre"
    for prefix in ("shot_", "first_impact_"):
        if metric.startswith(prefix) and metric[len(prefix) :] in QUANTITIES:
            return ("shot", *QUANTITIES[metric[len(prefix) :]])
    names = ", ".join(f"{p}{q}" for p in ("shot_", "first_impact_") for q in QUANTITIES)
    raise NoAnalyticModelError(
        f"metric {metric}: no analytical counterpart (those with one: {names}, {STRUCK})"
    )


@dataclass(frozen=True)
class ShotScene:
    """A shot's approach relative to its face (shot frame: normal n, tangent n turned +90°):
    v_n < 0 and v_t (m/s), spin (rad/s), the granule's mass (kg) and radius (m), the pair's
    restitution and friction as the case gives them, and which fitted key (index) sets each."""

    v_n: float
    v_t: float
    spin: float
    mass: float
    radius: float
    restitution: float
    friction: float
    restitution_key: int | None
    friction_key: int | None

    def impact(self, theta: np.ndarray) -> ObliqueImpact:
        """The oblique-impact law's outcome at the fitted vector ``theta``; its tangent is the
        shot frame's reversed (t × n = ẑ there)."""
        e = self.restitution if self.restitution_key is None else theta[self.restitution_key]
        f = self.friction if self.friction_key is None else theta[self.friction_key]
        return oblique_impact(
            self.mass, self.radius, self.v_n, -self.v_t, float(e), float(f), omega_g=self.spin
        )

    def metric(self, theta: np.ndarray, what: str, point: str) -> float:
        """e, β or the rebound angle (rad) at ``point`` (perga.stats.metrics's conventions)."""
        out = self.impact(theta)
        if what == "restitution":
            return -out.normal_velocity / self.v_n
        before = self.v_t if point == "centre" else self.v_t - self.spin * self.radius
        after = -out.tangential_velocity if point == "centre" else -out.slip_after
        if what == "angle":
            return rebound_angle(before, after, out.normal_velocity)
        return -after / before


def _target(case: Case) -> str:
    """The material a granule strikes: the chamber's for a wall shot, else the hammers'."""
    placement = case.granules.placement
    wall = isinstance(placement, ShotPlacement) and placement.target == "wall"
    return case.chamber.material if wall else case.hammers.material


def _pair(case: Case) -> tuple[float, float]:
    contact = case.contact(case.granules.material, _target(case))
    return contact.restitution, contact.friction


def _loader(case_path: Path, row: dict[str, Any]):
    def load(values: dict[str, Any]) -> Case:
        overrides = [f"{k}={toml_value(v)}" for k, v in {**row, **values}.items()]
        return load_case(case_path, overrides=overrides)

    return load


def _pair_keys(case_path: Path, row: dict[str, Any], fitted: dict[str, float]) -> dict[str, int]:
    """Which fitted key (index) is the struck pair's e ("e") and f ("f"), found by moving each;
    a key that moves neither has no place in the laws (refused)."""
    load = _loader(case_path, row)
    e, f = _pair(load(fitted))
    keys: dict[str, int] = {}
    for i, (key, value) in enumerate(fitted.items()):
        e1, f1 = _pair(load({**fitted, key: value / 2 if value else 0.5}))  # in range, moved
        which = "e" if e1 != e else "f" if f1 != f else None
        if which is None:
            raise NoAnalyticModelError(
                f"fitted key {key}: the analytical model takes the struck pair's restitution "
                "and friction only"
            )
        keys[which] = i
    return keys


def shot_scene(case_path: Path, row: dict[str, Any], fitted: dict[str, float]) -> ShotScene:
    """The shot of one data row: ``case_path`` with the row's conditions and the fitted keys
    at ``fitted`` (:func:`_pair_keys`)."""
    case = _loader(case_path, row)(fitted)
    placement = case.granules.placement
    if not isinstance(placement, ShotPlacement):
        raise NoAnalyticModelError(
            f"{case_path}: the shot metrics' analytical model is a shot's; granules.placement "
            "is not a shot"
        )
    face = shot_face(case, placement)
    _, velocity = shot(case, placement)
    u = velocity[0] - face.velocity
    n = face.normal
    t = np.array([-n[1], n[0]])
    e, f = _pair(case)
    keys = _pair_keys(case_path, row, fitted)
    return ShotScene(
        float(u @ n), float(u @ t), placement.spin, case.granule_mass, case.granules.radius,
        e, f, keys.get("e"), keys.get("f"),
    )  # fmt: skip


@dataclass(frozen=True)
class StruckScene:
    """A granule at rest struck head-on by a hinged hammer's face: the face's speed ωρ (m/s),
    the granule's mass and the hammer's effective mass there (kg), the pair's restitution and
    which fitted key (index) sets it."""

    face_speed: float
    mass: float
    hammer_mass: float
    restitution: float
    restitution_key: int | None

    def metric(self, theta: np.ndarray, what: str, point: str) -> float:
        """The granule's speed after the impact, m/s."""
        e = self.restitution if self.restitution_key is None else theta[self.restitution_key]
        impact = normal_impact(self.mass, self.hammer_mass, 0.0, self.face_speed, float(e))
        return impact.granule_velocity


def struck_scene(case_path: Path, row: dict[str, Any], fitted: dict[str, float]) -> StruckScene:
    """The struck granule of one data row (module doc): one granule placed explicitly, at rest,
    hammers hinged (else :class:`NoAnalyticModelError` saying which)."""
    case = _loader(case_path, row)(fitted)
    placement = case.granules.placement
    if (
        not isinstance(placement, ExplicitPlacement)
        or case.granules.count != 1
        or placement.velocities is not None
        or case.hammers.mount != "hinged"
    ):
        raise NoAnalyticModelError(
            f"{case_path}: {STRUCK}'s analytical model is one granule placed at rest "
            "(granules.placement kind explicit, count 1, no velocities) struck by hinged hammers"
        )
    rho = math.hypot(*placement.positions[0])
    arm = rho - case.hammers.hinge_radius
    moment = hammer_geometry(case).moment_about_hinge
    e, _ = _pair(case)
    return StruckScene(
        case.rotor.angular_velocity * rho, case.granule_mass, hinged_effective_mass(moment, arm),
        e, _pair_keys(case_path, row, fitted).get("e"),
    )  # fmt: skip


SCENES = {"shot": shot_scene, "struck": struck_scene}


@dataclass(frozen=True)
class AnalyticModel:
    """The analytical values of a calibration's metrics at every data row: a callable of the
    fitted vectors (n, keys) -> (n, rows, metrics) (:data:`perga.studies.surrogate.Cheap`)."""

    scenes: list[dict[str, ShotScene | StruckScene]]
    """Per data row, its scene of each kind the metrics need."""
    quantities: list[tuple[str, str, str]]

    def __call__(self, thetas: np.ndarray) -> np.ndarray:
        thetas = np.atleast_2d(thetas)
        return np.array(
            [
                [
                    [s[kind].metric(t, what, at) for kind, what, at in self.quantities]
                    for s in self.scenes
                ]
                for t in thetas
            ]
        )


def analytic_model(
    case_path: Path, conditions: list[dict[str, Any]], metrics: list[str], fitted: dict[str, float]
) -> AnalyticModel:
    """The analytical model of a calibration (module doc): each metric must have its law, the
    case its scene, the fitted keys be the struck pair's e and f (else
    :class:`NoAnalyticModelError` saying which)."""
    quantities = [_quantity(m) for m in metrics]
    kinds = {kind for kind, _, _ in quantities}
    scenes = [{k: SCENES[k](case_path, row, fitted) for k in kinds} for row in conditions]
    return AnalyticModel(scenes, quantities)
