"""Mass properties of closed meshes and extruded outlines against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from perga.analytic.hammer import PlateHammer
from perga.geometry import (
    GeometryError,
    extrude,
    extruded_properties,
    load_mesh,
    mesh_file_properties,
    mesh_mass_properties,
)

RHO = 7850.0  # kg/m³


def ngon_prism(radius: float, n: int, height: float) -> tuple[float, float]:
    """Mass (kg) and I_z about the axis (kg·m²) of a regular n-gon prism of circumradius r."""
    mass = RHO * height * 0.5 * n * radius**2 * math.sin(2 * math.pi / n)
    return mass, mass * radius**2 * (1 + 2 * math.cos(math.pi / n) ** 2) / 6


@pytest.mark.parametrize("suffix", ["stl", "obj"])
def test_plate_from_file_matches_closed_form(tmp_path, suffix):
    a, b, c = 150.0, 50.0, 10.0  # mm
    box = trimesh.creation.box(extents=[a, b, c])
    box.apply_translation([60.0, 0.0, 0.0])  # hinge at the origin, 15 mm from the inner end
    path = tmp_path / f"plate.{suffix}"
    box.export(path)
    props = mesh_file_properties(path, "mm", RHO)
    plate = PlateHammer(0.150, 0.050, 0.010, RHO, hinge_offset=0.015)
    assert props.mass == pytest.approx(RHO * 0.15 * 0.05 * 0.01, rel=1e-6)
    assert props.mass == pytest.approx(plate.mass, rel=1e-6)
    assert props.centre_of_mass == pytest.approx((0.060, 0.0), rel=1e-6, abs=1e-12)
    assert props.moment_about_centre == pytest.approx(plate.inertia_about_centre, rel=1e-6)
    assert props.moment_about((0.0, 0.0)) == pytest.approx(plate.inertia_about_hinge, rel=1e-6)


@pytest.mark.parametrize(("suffix", "sections"), [("stl", 64), ("obj", 256)])
def test_disc_from_file_matches_ngon_prism(tmp_path, suffix, sections):
    r, h = 0.15, 0.01  # m
    path = tmp_path / f"disc.{suffix}"
    trimesh.creation.cylinder(radius=r, height=h, sections=sections).export(path)
    props = mesh_file_properties(path, "m", RHO)
    mass, moment = ngon_prism(r, sections, h)
    assert props.mass == pytest.approx(mass, rel=1e-6)
    assert props.moment_about_centre == pytest.approx(moment, rel=1e-6)
    # the N-gon is not the circle: its relative error is O((π/N)²) (~2e-4 for N = 256)
    disc = RHO * math.pi * r**2 * h
    assert props.mass == pytest.approx(disc, rel=(math.pi / sections) ** 2)
    assert props.moment_about_centre == pytest.approx(
        disc * r**2 / 2, rel=2 * (math.pi / sections) ** 2
    )


def test_extruded_outline_matches_plate_and_mesh_route():
    outline = np.array([[-0.015, -0.025], [0.135, -0.025], [0.135, 0.025], [-0.015, 0.025]])
    props = extruded_properties(outline, 0.01, RHO)
    plate = PlateHammer(0.150, 0.050, 0.010, RHO, hinge_offset=0.015)
    assert props.mass == pytest.approx(plate.mass, rel=1e-12)
    assert props.moment_about((0, 0)) == pytest.approx(plate.inertia_about_hinge, rel=1e-12)
    # a concave part with a hole: the polygon formulas and the 3-D mesh agree
    stepped = (
        np.array(
            [[-15, -25], [75, -25], [75, -35], [135, -35], [135, 35], [75, 35], [75, 25], [-15, 25]]
        )
        * 1e-3
    )
    t = np.linspace(0, -2 * np.pi, 24, endpoint=False)
    hole = np.c_[np.cos(t), np.sin(t)] * 0.006 + [0.1, 0.0]
    flat = extruded_properties(stepped, 0.01, RHO, [hole])
    solid = mesh_mass_properties(extrude(stepped, 0.01, [hole]), RHO)
    assert solid.mass == pytest.approx(flat.mass, rel=1e-12)
    assert solid.centre_of_mass == pytest.approx(flat.centre_of_mass, rel=1e-12)
    assert solid.moment_about((0, 0)) == pytest.approx(flat.moment_about((0, 0)), rel=1e-12)


def test_open_mesh_is_refused(tmp_path):
    box = trimesh.creation.box(extents=[1, 1, 1])
    box.update_faces(np.arange(len(box.faces)) != 0)
    path = tmp_path / "open.stl"
    box.export(path)
    with pytest.raises(GeometryError, match=r"open.stl: the mesh is open \(not watertight\)"):
        load_mesh(path, "mm")


def test_non_manifold_mesh_is_refused(tmp_path):
    a = trimesh.creation.box(extents=[1, 1, 1])
    b = a.copy()
    b.apply_translation([1, 1, 0])  # shares one edge with a
    path = tmp_path / "bowtie.obj"
    trimesh.util.concatenate([a, b]).export(path)
    with pytest.raises(GeometryError, match=r"bowtie.obj: the mesh is non-manifold: 1 edge"):
        load_mesh(path, "mm")


def test_bad_units_and_density_are_refused(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=[1, 1, 1]).export(path)
    with pytest.raises(GeometryError, match=r"box\.stl: unknown units 'furlong'"):
        load_mesh(path, "furlong")
    with pytest.raises(ValueError, match="density must be finite and > 0"):
        mesh_file_properties(path, "mm", -1.0)
