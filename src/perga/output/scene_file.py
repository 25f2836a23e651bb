"""``scene.json``: the geometry of a run's system (hammers, rotor disc, chamber, granule radii),
written once at the start of a run so that readers of a run directory (``perga render``) draw
the machine from the run's own files instead of rebuilding it from the case. SI units."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from perga.model.system import System

FloatArray = NDArray[np.float64]
NAME = "scene.json"


@dataclass(frozen=True)
class HammerGeometry:
    """A hammer's outline in its own frame (hinge at the origin, axis +x), m; its hinge in the
    rotor frame, m; its polar angle on the rotor and its swing angle at the start, rad; its
    mount ('hinged', 'welded', 'free')."""

    outline: FloatArray
    hinge: tuple[float, float]
    angle_on_rotor: float
    swing_angle: float
    mount: str


@dataclass(frozen=True)
class SceneGeometry:
    """What ``scene.json`` holds: hammers; the rotor's radius and disc outline (None: a circle);
    the chamber's inner radius, inner outline (None: round) and wall thickness (None without
    a chamber); every granule's radius, m."""

    hammers: list[HammerGeometry]
    rotor_radius: float
    rotor_outline: FloatArray | None
    chamber_radius: float | None
    chamber_outline: FloatArray | None
    wall_thickness: float | None
    granule_radii: FloatArray


def write_scene(directory: Path, spec: System) -> Path:
    """Write ``directory/scene.json`` for ``spec``; returns its path."""
    c = spec.chamber
    data = {
        "hammers": [
            {
                "outline": [list(v) for v in h.outline],
                "hinge": list(h.hinge_position),
                "angle_on_rotor": h.angle_on_rotor,
                "swing_angle": h.swing_angle,
                "mount": h.mount,
            }
            for h in spec.hammers
        ],
        "rotor": {
            "radius": spec.rotor.radius,
            "outline": None
            if spec.rotor.outline is None
            else [list(v) for v in spec.rotor.outline],
        },
        "chamber": None
        if c is None
        else {
            "radius": c.radius,
            "outline": None if c.outline is None else [list(v) for v in c.outline],
            "wall_thickness": c.wall_thickness,
        },
        "granule_radii": [g.radius for g in spec.granules],
    }
    path = directory / NAME
    path.write_text(json.dumps(data) + "\n", encoding="utf-8")
    return path


def _points(value: list | None) -> FloatArray | None:
    return None if value is None else np.array(value, dtype=float).reshape(-1, 2)


def read_scene(directory: Path) -> SceneGeometry:
    """The geometry in ``directory/scene.json`` (FileNotFoundError naming it if absent)."""
    path = directory / NAME
    if not path.exists():
        raise FileNotFoundError(f"{path}: missing (a run writes it at its start)")
    data = json.loads(path.read_text(encoding="utf-8"))
    chamber = data["chamber"] or {}
    return SceneGeometry(
        hammers=[
            HammerGeometry(
                outline=np.array(h["outline"], dtype=float),
                hinge=(float(h["hinge"][0]), float(h["hinge"][1])),
                angle_on_rotor=float(h["angle_on_rotor"]),
                swing_angle=float(h["swing_angle"]),
                mount=str(h["mount"]),
            )
            for h in data["hammers"]
        ],
        rotor_radius=float(data["rotor"]["radius"]),
        rotor_outline=_points(data["rotor"]["outline"]),
        chamber_radius=chamber.get("radius"),
        chamber_outline=_points(chamber.get("outline")),
        wall_thickness=chamber.get("wall_thickness"),
        granule_radii=np.array(data["granule_radii"], dtype=float),
    )
