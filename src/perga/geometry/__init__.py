"""Part geometry from files: closed meshes (STL/OBJ) and 2-D outlines (points, SVG, DXF),
their rotor-plane sections, convex decomposition for Pymunk, and mass properties. SI units."""

from perga.geometry.convex import decompose, triangulate
from perga.geometry.extrude import extrude
from perga.geometry.mass import load_mesh, mesh_file_properties, mesh_mass_properties
from perga.geometry.outline import Outline, read_outline, validate_outline
from perga.geometry.properties import (
    AreaProperties,
    MassProperties,
    area_properties,
    extruded_properties,
)
from perga.geometry.section import Section, section_file, section_mesh
from perga.geometry.units import UNIT_SCALE, GeometryError

__all__ = [
    "UNIT_SCALE",
    "AreaProperties",
    "GeometryError",
    "MassProperties",
    "Outline",
    "Section",
    "area_properties",
    "decompose",
    "extrude",
    "extruded_properties",
    "load_mesh",
    "mesh_file_properties",
    "mesh_mass_properties",
    "read_outline",
    "section_file",
    "section_mesh",
    "triangulate",
    "validate_outline",
]
