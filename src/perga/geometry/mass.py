"""Closed 3-D meshes (STL, OBJ, ... via trimesh) of parts, and their mass properties.

The mesh's z axis is normal to the rotor plane. Files are read in their declared units and
scaled to metres. Units: m, kg, kg/m³, kg·m².
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from perga.geometry.properties import MassProperties
from perga.geometry.units import GeometryError, check_extent, unit_scale

if TYPE_CHECKING:
    import trimesh


def check_closed(mesh: trimesh.Trimesh, source: str) -> None:
    """GeometryError unless every edge of ``mesh`` joins exactly two faces, consistently wound."""
    if len(mesh.faces) == 0:
        raise GeometryError(f"{source}: the mesh has no faces")
    _, counts = np.unique(mesh.edges_sorted, axis=0, return_counts=True)
    open_edges, shared = int(np.sum(counts == 1)), int(np.sum(counts > 2))
    if shared:
        raise GeometryError(
            f"{source}: the mesh is non-manifold: {shared} edge(s) shared by more than two faces"
        )
    if open_edges:
        raise GeometryError(
            f"{source}: the mesh is open (not watertight): {open_edges} boundary edge(s) "
            "belong to one face only"
        )
    if not mesh.is_winding_consistent:
        raise GeometryError(f"{source}: the mesh's faces are not wound consistently")


def load_mesh(path: str | Path, units: str) -> trimesh.Trimesh:
    """Read a closed mesh file in ``units`` (e.g. 'mm'), scaled to metres, outward normals.

    GeometryError naming the file for an unreadable, empty, open or non-manifold mesh, or one
    beyond ±10 m (:func:`~perga.geometry.units.check_extent`).
    """
    import trimesh  # here, not at import: it costs half a second of every run's start

    source = str(path)
    scale = unit_scale(units, source)
    try:
        mesh = trimesh.load_mesh(path, process=True)
    except Exception as error:  # trimesh raises many types for bad files
        raise GeometryError(f"{source}: cannot read the mesh ({error})") from error
    if isinstance(mesh, trimesh.Scene):
        mesh = mesh.to_mesh() if mesh.geometry else trimesh.Trimesh()
    if not isinstance(mesh, trimesh.Trimesh):
        raise GeometryError(f"{source}: not a triangle mesh (got {type(mesh).__name__})")
    check_closed(mesh, source)
    mesh.apply_scale(scale)
    check_extent(mesh.vertices, source)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def mesh_mass_properties(mesh: trimesh.Trimesh, density: float) -> MassProperties:
    """Mass (kg), in-plane centre of mass (m) and I_z about the centre of mass (kg·m²) of a
    closed mesh in metres of uniform ``density`` (kg/m³)."""
    if not (math.isfinite(density) and density > 0):
        raise ValueError(f"density must be finite and > 0 kg/m³ (got {density})")
    props = mesh.mass_properties
    volume = float(props.volume)
    if not volume > 0:
        raise GeometryError(f"mesh volume must be > 0 m³ (got {volume})")
    # trimesh's inertia is about the centre of mass for unit density, computed exactly
    # for the polyhedron from its faces
    scale = density / float(props.density)
    centre = props.center_mass
    return MassProperties(
        mass=float(props.mass) * scale,
        centre_of_mass=(float(centre[0]), float(centre[1])),
        moment_about_centre=float(props.inertia[2, 2]) * scale,
    )


def mesh_file_properties(path: str | Path, units: str, density: float) -> MassProperties:
    """``mesh_mass_properties`` of the closed mesh file ``path`` declared in ``units``."""
    return mesh_mass_properties(load_mesh(path, units), density)
