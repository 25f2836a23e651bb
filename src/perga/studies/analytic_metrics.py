"""The analytical counterparts of a calibration's metrics, the cheap level of a two-fidelity
calibration (:mod:`perga.studies.surrogate`): a shot's rebound by the oblique-impact law.

A shot (``granules.placement.kind = "shot"``) at an immovable face, its restitution e and
friction f the pair's, gives by :func:`perga.analytic.impact.oblique_impact` (a disc, Brach
2007, Stronge 2000) the normal restitution, the tangential restitution and the rebound angle at
the centre and at the contact point, in the conventions of :mod:`perga.stats.metrics`. The law
leaves out what the simulation has and the surrogate's discrepancy learns: the face's motion and
mass (a hinged or turning hammer), a contact found a step deep, a soft contact's duration.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from perga.analytic.impact import ObliqueImpact, oblique_impact
from perga.case.load import load_case
from perga.case.schema import Case, ShotPlacement
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


def _quantity(metric: str) -> tuple[str, str]:
    for prefix in ("shot_", "first_impact_"):
        if metric.startswith(prefix) and metric[len(prefix) :] in QUANTITIES:
            return QUANTITIES[metric[len(prefix) :]]
    names = ", ".join(f"{p}{q}" for p in ("shot_", "first_impact_") for q in QUANTITIES)
    raise NoAnalyticModelError(
        f"metric {metric}: no analytical counterpart (those with one: {names})"
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


def _pair(case: Case, placement: ShotPlacement) -> tuple[float, float]:
    target = case.hammers.material if placement.target == "hammer" else case.chamber.material
    contact = case.contact(case.granules.material, target)
    return contact.restitution, contact.friction


def shot_scene(case_path: Path, row: dict[str, Any], fitted: dict[str, float]) -> ShotScene:
    """The scene of one data row: ``case_path`` with the row's conditions and the fitted keys
    at ``fitted``; which key is the pair's e or f is found by moving each (a key that moves
    neither, or that moves the shot itself, has no place in the law: refused)."""

    def load(values: dict[str, Any]) -> Case:
        return load_case(case_path, overrides=[f"{k}={toml_value(v)}" for k, v in values.items()])

    case = load({**row, **fitted})
    placement = case.granules.placement
    if not isinstance(placement, ShotPlacement):
        raise NoAnalyticModelError(
            f"{case_path}: the analytical model is a shot's; granules.placement is not a shot"
        )
    face = shot_face(case, placement)
    _, velocity = shot(case, placement)
    u = velocity[0] - face.velocity
    n = face.normal
    t = np.array([-n[1], n[0]])
    e, f = _pair(case, placement)
    keys: dict[str, int] = {}
    for i, (key, value) in enumerate(fitted.items()):
        moved = load({**row, **fitted, key: value + 0.5 * (1.0 - value)})
        e1, f1 = _pair(moved, moved.granules.placement)
        which = "e" if e1 != e else "f" if f1 != f else None
        if which is None:
            raise NoAnalyticModelError(
                f"fitted key {key}: the analytical model takes the shot pair's restitution and "
                "friction only"
            )
        keys[which] = i
    return ShotScene(
        float(u @ n), float(u @ t), placement.spin, case.granule_mass, case.granules.radius,
        e, f, keys.get("e"), keys.get("f"),
    )  # fmt: skip


@dataclass(frozen=True)
class AnalyticModel:
    """The analytical values of a calibration's metrics at every data row: a callable of the
    fitted vectors (n, keys) -> (n, rows, metrics) (:data:`perga.studies.surrogate.Cheap`)."""

    scenes: list[ShotScene]
    quantities: list[tuple[str, str]]

    def __call__(self, thetas: np.ndarray) -> np.ndarray:
        thetas = np.atleast_2d(thetas)
        return np.array(
            [[[s.metric(t, *q) for q in self.quantities] for s in self.scenes] for t in thetas]
        )


def analytic_model(
    case_path: Path, conditions: list[dict[str, Any]], metrics: list[str], fitted: dict[str, float]
) -> AnalyticModel:
    """The analytical model of a calibration (module doc): its metrics must be shot rebound
    metrics, its case a shot, its fitted keys the pair's e and f (else
    :class:`NoAnalyticModelError` saying which)."""
    quantities = [_quantity(m) for m in metrics]
    return AnalyticModel([shot_scene(case_path, row, fitted) for row in conditions], quantities)
