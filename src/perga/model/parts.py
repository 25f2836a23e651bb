"""The rotor disc and the chamber of a case as geometry (SI), round or from geometry files.

Files are drawn in the rotor frame, the rotor axis at the origin. A chamber file gives the wall's
inner outline: a 2-D outline (.txt points, .svg, .dxf), or a closed mesh whose section by the
plane half-way up it is a ring (its one hole is the inner outline). A rotor file gives the disc:
a mesh's section (its holes are the hinge holes) or an outline (no holes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from perga.case.schema import Case, PartFile
from perga.geometry.mass import load_mesh
from perga.geometry.outline import read_outline
from perga.geometry.polygon import FloatArray, contains, vertex_tuples
from perga.geometry.properties import area_properties
from perga.geometry.section import Section, section_mesh
from perga.geometry.units import GeometryError
from perga.model.hammer_geometry import MESH_SUFFIXES, resolve_path
from perga.model.system import ChamberSpec


@dataclass(frozen=True)
class ChamberGeometry:
    """outline: the wall's inner outline, counter-clockwise, m (None: a circle of
    ``inner_radius``); inner_radius: nearest point of the wall to the axis, m; outer_radius:
    farthest point of the inner outline from the axis, m; source: the file, or "round"."""

    outline: FloatArray | None
    inner_radius: float
    outer_radius: float
    source: str


@dataclass(frozen=True)
class RotorGeometry:
    """outline: the disc, counter-clockwise, m; hinges: centres of its hinge holes (k, 2), m;
    radius: farthest point of the disc from the axis, m; thickness: the mesh's height, m (None
    for an outline); source: the file."""

    outline: FloatArray
    hinges: FloatArray
    radius: float
    thickness: float | None
    source: str


def _segment_distances(outline: FloatArray) -> FloatArray:
    """Distance of the origin from each edge of ``outline``, m."""
    a, b = outline, np.roll(outline, -1, axis=0)
    e = b - a
    t = np.clip(-np.einsum("ij,ij->i", a, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
    return np.hypot(*(a + t[:, None] * e).T)


def _section(path: str, part: PartFile) -> tuple[Section, float | None]:
    if Path(path).suffix.lower() in MESH_SUFFIXES:
        mesh = load_mesh(path, part.units)
        return section_mesh(mesh, None, path), float(mesh.extents[2])
    return Section(read_outline(path, part.units).vertices, ()), None


def chamber_geometry(case: Case) -> ChamberGeometry | None:
    """The chamber of ``case`` (None without one). Raises GeometryError naming the file."""
    chamber = case.chamber
    if chamber is None:
        return None
    if chamber.shape is None:
        assert chamber.radius is not None
        return ChamberGeometry(None, chamber.radius, chamber.radius, "round")
    return _chamber_file(str(resolve_path(case.source_dir, chamber.shape)), chamber.shape)


def chamber_spec(case: Case) -> ChamberSpec:
    """The chamber of ``case`` as the system has it (a case with a chamber)."""
    c, g = case.chamber, chamber_geometry(case)
    assert c is not None and g is not None
    outline = None if g.outline is None else vertex_tuples(g.outline)
    return ChamberSpec(g.inner_radius, c.wall_thickness, c.material, outline=outline)


@lru_cache(maxsize=16)
def _chamber_file(path: str, part: PartFile) -> ChamberGeometry:
    section, _ = _section(path, part)
    if Path(path).suffix.lower() in MESH_SUFFIXES:
        if len(section.holes) != 1:
            raise GeometryError(
                f"{path}: a chamber mesh must be a ring (one hole in its section, the inside "
                f"of the wall); its section has {len(section.holes)} holes"
            )
        inner = section.holes[0][::-1].copy()
    else:
        inner = section.outline
    if not contains(inner, (0.0, 0.0)):
        raise GeometryError(f"{path}: the rotor axis (0, 0) is not inside the chamber outline")
    return ChamberGeometry(
        outline=inner,
        inner_radius=float(_segment_distances(inner).min()),
        outer_radius=float(np.hypot(*inner.T).max()),
        source=path,
    )


def rotor_geometry(case: Case) -> RotorGeometry | None:
    """The rotor disc of ``case`` from its file (None for a plain ``rotor.radius``)."""
    shape = case.rotor.shape
    if shape is None:
        return None
    return _rotor_file(str(resolve_path(case.source_dir, shape)), shape)


@lru_cache(maxsize=16)
def _rotor_file(path: str, part: PartFile) -> RotorGeometry:
    section, thickness = _section(path, part)
    hinges = np.array(
        [area_properties(hole[::-1]).centroid for hole in section.holes], dtype=float
    ).reshape(-1, 2)
    return RotorGeometry(
        outline=section.outline,
        hinges=hinges,
        radius=float(np.hypot(*section.outline.T).max()),
        thickness=thickness,
        source=path,
    )


def hinge_misses(case: Case, hinges: list[tuple[float, float]], tol: float = 1e-6) -> list[int]:
    """Indices of the hammer hinges (rotor frame, m) that sit at no hinge hole of the case's
    rotor file (within ``tol`` m); empty without a rotor file or without holes."""
    rotor = rotor_geometry(case)
    if rotor is None or len(rotor.hinges) == 0:
        return []
    return [
        k
        for k, (x, y) in enumerate(hinges)
        if np.min(np.hypot(rotor.hinges[:, 0] - x, rotor.hinges[:, 1] - y)) > tol
    ]


def hammer_angles(case: Case) -> tuple[float, ...]:
    """Each hammer's hinge angle on the rotor, rad: ``hammers.angles``, or evenly spaced."""
    h = case.hammers
    return h.angles or tuple(2 * math.pi * i / h.count for i in range(h.count))


def hinge_positions(case: Case) -> list[tuple[float, float]]:
    """Each hammer's hinge in the rotor frame at t = 0, m (at ``hammers.hinge_radius``)."""
    r = case.hammers.hinge_radius
    return [(r * math.cos(a), r * math.sin(a)) for a in hammer_angles(case)]
