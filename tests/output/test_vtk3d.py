"""perga.output.vtk3d (output.vtk_3d): the extruded machine read back by meshio and pyvista.

Tolerances: volumes to 1e-9 relative (the brief's bound; trimesh's signed-volume sum of a
closed mesh against area × thickness, both exact up to round-off ~1e-15); poses to 1e-12 m
(the 3-D vertices are rotated by numpy, the 2-D ones by Pymunk's local_to_world: two round-offs
of ~1e-17 m on 0.2 m coordinates); z extents exactly (±t/2 written as computed).
"""

from __future__ import annotations

import dataclasses
import json
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import meshio
import numpy as np
import pytest
import pyvista as pv
import trimesh

from perga.case import load_case
from perga.case.schema import Case
from perga.cli import main
from perga.engine import Simulation
from perga.geometry.polygon import outline_or_circle, signed_area
from perga.geometry.wall import wall_pieces
from perga.model.compile import compile_case
from perga.model.hammer_geometry import hammer_geometry
from perga.model.parts import rotor_geometry
from perga.model.system import DrawingSpec
from perga.output.vtk import CHAMBER_SEGMENTS, ROTOR_SIDES, VtkRecorder
from tests.output.test_vtk import Frame, both, read_pvd, snapshot

CASES = Path(__file__).parents[2] / "cases"
FRAMES = 8
STEPS_PER_FRAME = 40
POSE_ATOL = 1e-12
VOLUME_RTOL = 1e-9
FILES_3D = ("hammers3d.pvd", "rotor3d.pvd", "chamber3d.vtu")


def with_3d(case: Case) -> Case:
    """``case`` with output.vtk_3d = true (geometry paths still from its folder)."""
    output = case.output.model_copy(update={"vtk_3d": True})
    return case.model_copy(update={"output": output})


@dataclass
class Run3D:
    sim: Simulation
    directory: Path
    frames: list[Frame]
    drawing: DrawingSpec


@pytest.fixture(scope="module")
def run3d(tmp_path_factory: pytest.TempPathFactory) -> Run3D:
    """The separator (six plate hammers, 300 granules), each hammer drawn with its own
    thickness so that a mix-up between hammers shows."""
    spec = compile_case(with_3d(load_case(CASES / "separator.toml")))
    assert spec.drawing is not None
    drawing = dataclasses.replace(
        spec.drawing, hammer_thickness=tuple(0.003 + 0.001 * k for k in range(len(spec.hammers)))
    )
    sim = Simulation(dataclasses.replace(spec, drawing=drawing))
    directory = tmp_path_factory.mktemp("run3d")
    recorder = VtkRecorder(directory, sim.spec)
    frames = []
    for k in range(FRAMES):
        for _ in range(STEPS_PER_FRAME if k else 0):
            sim.step()
        frames.append(snapshot(sim))
        recorder.record(sim.frame(), sim.events())
    recorder.close()
    return Run3D(sim, directory / "vtk", frames, drawing)


def test_drawing_from_case() -> None:
    """Plates: the plate's thickness; files: the geometry's; rotor: its mesh's height, else the
    hammers'; chamber: the tallest part; granules: the case's thickness; none without the
    option."""
    separator = load_case(CASES / "separator.toml")
    assert compile_case(separator).drawing is None
    d = compile_case(with_3d(separator)).drawing
    plate = separator.hammer_plate.thickness
    assert d == DrawingSpec(
        (plate,) * 6, plate, max(plate, separator.granule_thickness), separator.granule_thickness
    )
    for name in ("plate-hammers-soft", "geometry-hammers"):
        case = load_case(CASES / f"{name}.toml")
        d = compile_case(with_3d(case)).drawing
        hammer = hammer_geometry(case).thickness
        disc = rotor_geometry(case)
        rotor = hammer if disc is None else disc.thickness
        assert d.hammer_thickness == (hammer,) * case.hammers.count
        assert d.rotor_thickness == rotor
        assert d.chamber_height == max(hammer, rotor, case.granule_thickness)
    assert rotor_geometry(load_case(CASES / "plate-hammers-soft.toml")).thickness == 0.01


def test_option_needs_vtk() -> None:
    with pytest.raises(ValueError, match="vtk_3d = true needs 'vtk'"):
        type(load_case(CASES / "separator.toml").output)(record=("granules",), vtk_3d=True)


def test_3d_series_have_the_2d_times(run3d: Run3D) -> None:
    for part in ("hammers", "rotor"):
        entries = read_pvd(run3d.directory / f"{part}3d.pvd")
        expected = [(f.time, f"{part}3d_{k:06d}.vtu") for k, f in enumerate(run3d.frames)]
        assert entries == expected
        assert [t for t, _ in read_pvd(run3d.directory / f"{part}.pvd")] == [t for t, _ in entries]


def part_cells(mesh: pv.UnstructuredGrid, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points (k, 3) and triangles (m, 3) of the cells ``cells`` (a mask)."""
    triangles = np.array([mesh.get_cell(int(c)).point_ids for c in np.flatnonzero(cells)])
    used, inverse = np.unique(triangles, return_inverse=True)
    return mesh.points[used], inverse.reshape(triangles.shape)


def test_hammers3d_and_rotor3d_round_trip(run3d: Run3D) -> None:
    """Each hammer (cells of its ``id``) and the rotor disc: a closed mesh of its outline's
    area times its thickness, both caps the 2-D file's polygon, every triangle with the 2-D
    file's cell data."""
    d = run3d.drawing
    spec = run3d.sim.spec
    disc = outline_or_circle(None, spec.rotor.radius, ROTOR_SIDES)
    series = [read_pvd(run3d.directory / name) for name in ("hammers3d.pvd", "rotor3d.pvd")]
    flat = [read_pvd(run3d.directory / name) for name in ("hammers.pvd", "rotor.pvd")]
    for (_, h3), (_, r3), (_, h2), (_, r2), frame in zip(*series, *flat, run3d.frames, strict=True):
        for file3d, file2d, hammers in ((h3, h2, True), (r3, r2, False)):
            m, p = both(run3d.directory / file3d)
            flat2d = pv.read(run3d.directory / file2d)
            assert set(p.celltypes) == {pv.CellType.TRIANGLE}
            assert [c.type for c in m.cells] == ["triangle"]
            np.testing.assert_array_equal(m.points, p.points)
            parts = range(len(spec.hammers)) if hammers else [0]
            for k in parts:
                cells = p.cell_data["id"] == k if hammers else np.ones(p.n_cells, dtype=bool)
                thickness = d.hammer_thickness[k] if hammers else d.rotor_thickness
                points, triangles = part_cells(p, cells)
                mesh = trimesh.Trimesh(points, triangles, process=False)
                assert mesh.is_watertight and mesh.is_winding_consistent
                # the 2-D pose: the simulation's for hammers (checked against the file in
                # test_vtk), the file's polygon for the rotor
                outline2d = (
                    frame.hammer_vertices[k]
                    if hammers
                    else flat2d.points[flat2d.get_cell(0).point_ids, :2]
                )
                area = abs(signed_area(outline2d if hammers else disc))
                assert mesh.volume == pytest.approx(area * thickness, rel=VOLUME_RTOL)
                assert points[:, 2].min() == -0.5 * thickness
                assert points[:, 2].max() == 0.5 * thickness
                # posed as in 2-D: both caps are the 2-D polygon, vertex for vertex
                for z in (-0.5 * thickness, 0.5 * thickness):
                    cap = points[points[:, 2] == z, :2]
                    assert len(cap) == len(outline2d)
                    gap = np.linalg.norm(cap[:, None, :] - outline2d[None, :, :], axis=2)
                    assert gap.min(axis=1).max() < POSE_ATOL
                    assert gap.min(axis=0).max() < POSE_ATOL
                # every triangle carries its part's 2-D cell data
                assert sorted(p.cell_data.keys()) == sorted(flat2d.cell_data.keys())
                for name in flat2d.cell_data:
                    values = p.cell_data[name][cells]
                    assert np.all(values == flat2d.cell_data[name][k]), name
                    meshio_values = np.concatenate(m.cell_data[name])[cells]
                    np.testing.assert_array_equal(meshio_values, values)
    # the rotor turned and the hammers swung: poses are not all the start's
    assert run3d.frames[-1].rotor_angle > 0.1


def test_chamber3d_is_the_closed_wall(run3d: Run3D) -> None:
    c = run3d.sim.spec.chamber
    h = run3d.drawing.chamber_height
    m, p = both(run3d.directory / "chamber3d.vtu")
    np.testing.assert_array_equal(m.points, p.points)
    triangles = np.array([p.get_cell(i).point_ids for i in range(p.n_cells)])
    mesh = trimesh.Trimesh(p.points, triangles, process=False)
    assert mesh.is_watertight and mesh.is_winding_consistent
    inner = outline_or_circle(None, c.radius, CHAMBER_SEGMENTS)
    _, outer = wall_pieces(inner, c.wall_thickness)
    area = abs(signed_area(outer)) - abs(signed_area(inner))
    assert mesh.volume == pytest.approx(area * h, rel=VOLUME_RTOL)
    assert p.bounds[4:] == (-0.5 * h, 0.5 * h)
    radius = np.hypot(p.points[:, 0], p.points[:, 1])
    np.testing.assert_allclose(radius.min(), c.radius, rtol=1e-15)


def test_granules_carry_their_thickness(run3d: Run3D) -> None:
    for _, file in read_pvd(run3d.directory / "granules.pvd"):
        m, p = both(run3d.directory / file)
        for data in (m.point_data, p.point_data):
            assert np.all(data["thickness"] == run3d.drawing.granule_thickness)


def short_separator(tmp_path: Path, vtk_3d: bool) -> Path:
    text = (CASES / "separator.toml").read_text().replace("duration = 0.5", "duration = 0.004")
    text += f"\n[output]\nvtk_3d = {json.dumps(vtk_3d)}\n"
    path = tmp_path / f"separator-{vtk_3d}.toml"
    path.write_text(text.replace('"../geometry', f'"{CASES.parent / "geometry"}'))
    return path


@pytest.mark.parametrize("vtk_3d", [True, False])
def test_perga_run_writes_3d_only_when_asked(tmp_path: Path, vtk_3d: bool) -> None:
    run = tmp_path / "run"
    assert main(["run", str(short_separator(tmp_path, vtk_3d)), "-o", str(run), "--quiet"]) == 0
    vtk = run / "vtk"
    found = sorted(f.name for f in vtk.iterdir() if "3d" in f.name)
    granules = pv.read(vtk / "granules_000000.vtu")
    if not vtk_3d:
        assert found == []
        assert "thickness" not in granules.point_data
        return
    hammers = read_pvd(vtk / "hammers.pvd")
    assert [t for t, _ in hammers] == pytest.approx([0.0, 0.001, 0.002, 0.003, 0.004])
    frames = [f"{part}3d_{k:06d}.vtu" for part in ("hammers", "rotor") for k in range(len(hammers))]
    assert found == sorted([*FILES_3D, *frames])
    for part in ("hammers3d", "rotor3d"):
        assert [t for t, _ in read_pvd(vtk / f"{part}.pvd")] == [t for t, _ in hammers]
        assert ET.parse(vtk / f"{part}.pvd").getroot().get("type") == "Collection"
    assert "thickness" in granules.point_data
    assert meshio.read(vtk / "chamber3d.vtu").points.shape[1] == 3
