"""Every bundled geometry file loads, and the meshes match their closed forms."""

from __future__ import annotations

import math
import runpy
from pathlib import Path

import numpy as np
import pytest

from perga.analytic.hammer import PlateHammer
from perga.geometry import (
    decompose,
    extruded_properties,
    load_mesh,
    mesh_mass_properties,
    read_outline,
    section_mesh,
)

ROOT = Path(__file__).resolve().parents[2] / "geometry"
RHO = 7850.0  # kg/m³, steel
MAKE = runpy.run_path(str(ROOT / "make_bundled.py"))


def test_plate_hammer_matches_closed_form():
    props = mesh_mass_properties(load_mesh(ROOT / "plate_hammer.stl", "mm"), RHO)
    plate = PlateHammer(0.150, 0.050, 0.010, RHO, hinge_offset=0.015)
    assert props.mass == pytest.approx(plate.mass, rel=1e-6)
    assert props.moment_about((0, 0)) == pytest.approx(plate.inertia_about_hinge, rel=1e-6)


@pytest.mark.parametrize("holes", [4, 8])
def test_rotor_disc_matches_polygon_closed_form(holes):
    props = mesh_mass_properties(load_mesh(ROOT / f"rotor_disc_{holes}_holes.stl", "mm"), RHO)

    def prism(r, n):  # regular n-gon prism, 10 mm thick: mass, I_z about its axis
        m = RHO * 0.01 * 0.5 * n * r**2 * math.sin(2 * math.pi / n)
        return m, m * r**2 * (1 + 2 * math.cos(math.pi / n) ** 2) / 6

    disc_m, disc_i = prism(0.150, 256)
    hole_m, hole_i = prism(0.008, 48)
    mass = disc_m - holes * hole_m
    moment = disc_i - holes * (hole_i + hole_m * 0.120**2)
    assert props.mass == pytest.approx(mass, rel=1e-6)  # float32 STL vertices: ~1e-7
    assert props.moment_about_centre == pytest.approx(moment, rel=1e-6)
    assert np.hypot(*props.centre_of_mass) < 1e-9
    assert len(section_mesh(load_mesh(ROOT / f"rotor_disc_{holes}_holes.stl", "mm")).holes) == (
        holes
    )


@pytest.mark.parametrize("name", ["plate_hammer.stl", "stepped_hammer.stl"])
def test_hammer_meshes_section_and_decompose(name):
    mesh = load_mesh(ROOT / name, "mm")
    section = section_mesh(mesh, 0.0)
    flat = extruded_properties(section.outline, 0.010, RHO)
    solid = mesh_mass_properties(mesh, RHO)
    assert flat.mass == pytest.approx(solid.mass, rel=1e-6)
    assert flat.moment_about((0, 0)) == pytest.approx(solid.moment_about((0, 0)), rel=1e-6)
    assert 0.3 < solid.mass < 1.0 and solid.centre_of_mass[0] > 0  # kg; head beyond the hinge
    assert len(decompose(section.outline)) == (1 if name.startswith("plate") else 2)


@pytest.mark.parametrize("name", ["rounded_hammer.svg", "rounded_hammer.dxf"])
def test_rounded_hammer_outlines(name):
    outline = read_outline(ROOT / name, "mm", hinge=(0.0, 0.0))
    expected = MAKE["rounded_outline"]() * 1e-3
    props = extruded_properties(outline.vertices, 0.010, RHO)
    assert props.mass == pytest.approx(extruded_properties(expected, 0.010, RHO).mass, rel=1e-9)
    assert outline.vertices[:, 0].max() == pytest.approx(0.135)
    assert len(decompose(outline.vertices)) == 1


@pytest.mark.parametrize("name", ["chamber_round.txt", "chamber_screen.svg"])
def test_chamber_outlines(name):
    outline = read_outline(ROOT / name, "mm", hinge=(0.0, 0.0))
    radii = np.hypot(*outline.vertices.T)
    assert radii.max() == pytest.approx(0.380 if "screen" in name else 0.300, rel=0.05)
    assert all(len(p) >= 3 for p in decompose(outline.vertices))


def test_bundled_files_are_reproducible(tmp_path):
    MAKE["main"](tmp_path)
    for path in sorted(ROOT.iterdir()):
        if path.suffix in (".stl", ".svg", ".dxf", ".txt"):
            assert (tmp_path / path.name).read_bytes() == path.read_bytes(), path.name
