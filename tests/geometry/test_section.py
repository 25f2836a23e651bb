"""Rotor-plane sections of closed meshes."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from perga.geometry import GeometryError, area_properties, extrude, section_mesh
from perga.geometry.polygon import signed_area


def test_box_section_is_its_rectangle():
    box = trimesh.creation.box(extents=[0.15, 0.05, 0.01])
    section = section_mesh(box, 0.001)
    assert len(section.outline) == 4 and section.holes == ()
    assert signed_area(section.outline) == pytest.approx(0.15 * 0.05, rel=1e-12)


def test_section_recovers_outline_and_holes():
    outline = np.array([[0, 0], [3, 0], [3, 1], [1, 1], [1, 2], [0, 2.0]])
    hole = np.array([[0.4, 0.4], [0.4, 0.6], [0.6, 0.6], [0.6, 0.4]])
    section = section_mesh(extrude(outline, 0.5, [hole]))
    assert len(section.outline) == 6 and len(section.holes) == 1
    got = area_properties(section.outline, section.holes)
    want = area_properties(outline, [hole])
    assert got.area == pytest.approx(want.area, rel=1e-12)
    assert got.polar_moment_about_centroid == pytest.approx(
        want.polar_moment_about_centroid, rel=1e-12
    )


@pytest.mark.parametrize("height", [0.02, -0.5, 0.005])
def test_plane_that_misses_is_refused(height):
    box = trimesh.creation.box(extents=[0.15, 0.05, 0.01])
    with pytest.raises(GeometryError, match=r"part.stl: the section plane z = .* misses the mesh"):
        section_mesh(box, height, source="part.stl")


def test_open_mesh_section_is_refused():
    box = trimesh.creation.box(extents=[1, 1, 1])
    box.update_faces(np.arange(len(box.faces)) != 0)
    with pytest.raises(GeometryError, match="the mesh is open"):
        section_mesh(box)


def test_two_separate_parts_are_refused():
    a = trimesh.creation.box(extents=[1, 1, 1])
    b = a.copy()
    b.apply_translation([3, 0, 0])
    with pytest.raises(GeometryError, match="not all inside the largest one"):
        section_mesh(trimesh.util.concatenate([a, b]))
