"""The hammer of a case as geometry: outline in the hammer frame and mass properties (SI).

A plate (``hammers.shape.kind = "plate"``) from its closed forms (:class:`~perga.analytic.
hammer.PlateHammer`); a file shape from :mod:`perga.geometry`: a closed mesh gives its section by
the rotor plane and its mass properties with the hammer material's density, a 2-D outline its
extrusion to ``thickness``. Either way the hinge is the origin of the file's frame and the
hammer axis is +x. A concave outline is split into convex pieces by the engine
(:class:`~perga.model.system.HammerSpec`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from perga.case.schema import Case, FileShape, PartFile, PlateShape
from perga.geometry.mass import load_mesh, mesh_mass_properties
from perga.geometry.outline import read_outline
from perga.geometry.polygon import counter_clockwise
from perga.geometry.properties import MassProperties, extruded_properties
from perga.geometry.section import section_mesh

MESH_SUFFIXES = (".stl", ".obj", ".ply", ".off")
Vec2 = tuple[float, float]


@dataclass(frozen=True)
class HammerGeometry:
    """outline: simple polygon, counter-clockwise, hammer frame, m; mass, kg;
    moment_about_hinge, kg·m²; centre_of_mass: hammer frame, m; thickness: out of the plane,
    m; tip: largest distance of the outline along the axis from the hinge, m; source: the
    file, or "plate"."""

    outline: tuple[Vec2, ...]
    mass: float
    moment_about_hinge: float
    centre_of_mass: Vec2
    thickness: float
    tip: float
    source: str

    def reach(self, hinge_radius: float) -> float:
        """Farthest distance of the outline from the rotor axis with the hammer radial, m."""
        return max(math.hypot(hinge_radius + x, y) for x, y in self.outline)


def resolve_path(case_dir: Path | None, shape: FileShape | PartFile) -> Path:
    """The geometry file of ``shape``: absolute, or relative to the case file's folder."""
    path = Path(shape.path)
    return path if path.is_absolute() or case_dir is None else case_dir / path


def hammer_geometry(case: Case) -> HammerGeometry:
    """The hammer of ``case`` (relative paths from ``case.source_dir``). Raises ValueError (a
    GeometryError naming the file) for unusable geometry."""
    density = case.materials[case.hammers.material].density
    shape = case.hammers.shape
    if isinstance(shape, PlateShape):
        plate = case.hammer_plate
        x0, x1, y = -shape.hinge_offset, shape.length - shape.hinge_offset, shape.width / 2
        return HammerGeometry(
            outline=((x0, -y), (x1, -y), (x1, y), (x0, y)),
            mass=plate.mass,
            moment_about_hinge=plate.inertia_about_hinge,
            centre_of_mass=(plate.hinge_to_centre_of_mass, 0.0),
            thickness=plate.thickness,
            tip=plate.tip_distance,
            source="plate",
        )
    return _from_file(str(resolve_path(case.source_dir, shape)), shape, density)


@lru_cache(maxsize=16)
def _from_file(path: str, shape: FileShape, density: float) -> HammerGeometry:
    if Path(path).suffix.lower() in MESH_SUFFIXES:
        mesh = load_mesh(path, shape.units)
        outline = section_mesh(mesh, shape.height, path).outline
        props: MassProperties = mesh_mass_properties(mesh, density)
        thickness = float(mesh.extents[2])
    else:
        if shape.thickness is None:
            raise ValueError(f"{path}: an outline needs hammers.shape.thickness (m)")
        outline = read_outline(path, shape.units, hinge=(0.0, 0.0)).vertices
        props = extruded_properties(outline, shape.thickness, density)
        thickness = shape.thickness
    points = counter_clockwise(outline)
    return HammerGeometry(
        outline=tuple((float(x), float(y)) for x, y in points),
        mass=props.mass,
        moment_about_hinge=props.moment_about((0.0, 0.0)),
        centre_of_mass=(float(props.centre_of_mass[0]), float(props.centre_of_mass[1])),
        thickness=thickness,
        tip=float(points[:, 0].max()),
        source=path,
    )
