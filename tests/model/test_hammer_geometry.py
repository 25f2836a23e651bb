"""Hammers from geometry files in case files (perga.model.hammer_geometry): the same hammer as a
plate and as a mesh gives the same engine hammer; a concave (stepped) hammer becomes convex
pieces; missing files are refused."""

import math
from pathlib import Path

import pytest

from perga.case import CaseError
from perga.cli import main
from perga.model.compile import compile_case, validated
from tests.case_text import case_text

ROOT = Path(__file__).resolve().parents[2]
SINGLE = case_text(ROOT / "cases" / "single-granule.toml")
PLATE = "mass = 0.02826\nhinge_radius = 0.08"
# geometry/plate_hammer.stl: 150 x 50 x 10 mm steel, hinge 15 mm from the inner end
PLATE_STL_AS_PLATE = (
    "mass = 0.58875\nhinge_radius = 0.03",
    'shape = { kind = "plate", length = 0.15, width = 0.05, hinge_offset = 0.015 }',
)


def _case(tmp_path: Path, hammers: tuple[str, str], name: str = "case.toml"):
    text = SINGLE.replace(PLATE, hammers[0]).replace(
        'shape = { kind = "plate", length = 0.06, width = 0.02, hinge_offset = 0.005 }',
        hammers[1],
    )
    path = tmp_path / name
    path.write_text(text)
    return path


def _file_shape(path: str, extra: str = "") -> tuple[str, str]:
    return (
        "hinge_radius = 0.03",
        f'shape = {{ kind = "file", path = "{path}", units = "mm"{extra} }}',
    )


def test_mesh_hammer_equals_the_same_plate(tmp_path):
    """The bundled plate mesh and the plate of its dimensions: outline, mass, I_A and centre of
    mass within 1e-6 (the mesh's float32 coordinates; mass properties tests: tests/geometry)."""
    stl = ROOT / "geometry" / "plate_hammer.stl"
    plate = compile_case(validated(_case(tmp_path, PLATE_STL_AS_PLATE, "plate.toml"))).hammers[0]
    mesh = compile_case(validated(_case(tmp_path, _file_shape(str(stl)), "mesh.toml"))).hammers[0]
    assert mesh.mass == pytest.approx(plate.mass, rel=1e-6)
    assert mesh.moment_about_hinge == pytest.approx(plate.moment_about_hinge, rel=1e-6)
    assert mesh.centre_of_mass == pytest.approx(plate.centre_of_mass, abs=1e-9)
    flat = [c for vertex in sorted(mesh.outline) for c in vertex]
    assert flat == pytest.approx([c for vertex in sorted(plate.outline) for c in vertex], abs=1e-9)


def test_relative_paths_start_at_the_case_file(tmp_path):
    folder = tmp_path / "cases"
    folder.mkdir()
    (tmp_path / "shapes").mkdir()
    svg = (ROOT / "geometry" / "rounded_hammer.svg").read_text()
    (tmp_path / "shapes" / "rounded.svg").write_text(svg)
    case = validated(_case(folder, _file_shape("../shapes/rounded.svg", ", thickness = 0.01")))
    hammer = compile_case(case).hammers[0]
    # a 50 mm bar from x = -15 to 110 mm plus a half disc of 25 mm drawn with 32 segments,
    # 10 mm thick steel (geometry/README.md)
    area = 0.125 * 0.05 + 0.5 * 32 * 0.025**2 * math.sin(math.pi / 32)
    assert hammer.mass == pytest.approx(7850 * 0.01 * area, rel=1e-9)


def test_stepped_hammer_is_two_convex_pieces(tmp_path):
    """geometry/stepped_hammer.stl: a 50 mm shank (x = -15 .. 75 mm) and a 70 mm head (x = 75 ..
    135 mm), 10 mm thick steel; mass, centre of mass and I_A from the two rectangles (1e-6: the
    mesh's float32 coordinates)."""
    stl = ROOT / "geometry" / "stepped_hammer.stl"
    hammer = compile_case(validated(_case(tmp_path, _file_shape(str(stl))))).hammers[0]
    parts = [(-0.015, 0.075, 0.05), (0.075, 0.135, 0.07)]  # x0, x1, width
    masses = [7850 * 0.01 * (x1 - x0) * w for x0, x1, w in parts]
    centres = [(x0 + x1) / 2 for x0, x1, _ in parts]
    moment = sum(
        m * ((x1 - x0) ** 2 + w**2) / 12 + m * c**2
        for m, c, (x0, x1, w) in zip(masses, centres, parts, strict=True)
    )
    assert hammer.mass == pytest.approx(sum(masses), rel=1e-6)
    assert hammer.centre_of_mass[0] == pytest.approx(
        sum(m * c for m, c in zip(masses, centres, strict=True)) / sum(masses), rel=1e-6
    )
    assert hammer.moment_about_hinge == pytest.approx(moment, rel=1e-6)
    assert len(hammer.pieces) == 2


def test_missing_file_and_mass_given_are_refused(tmp_path):
    with pytest.raises(CaseError) as info:
        validated(_case(tmp_path, _file_shape("nowhere.stl")))
    assert any("hammers.shape" in p and "nowhere.stl" in p for p in info.value.problems)
    hammers = ("mass = 0.1\n" + _file_shape("x.stl")[0], _file_shape("x.stl")[1])
    with pytest.raises(CaseError) as info:
        validated(_case(tmp_path, hammers))
    assert any("a file shape's mass follows from its geometry" in p for p in info.value.problems)


def test_bundled_geometry_case_runs_and_renders(tmp_path):
    text = (ROOT / "cases" / "geometry-hammers.toml").read_text()
    case = tmp_path / "case.toml"
    case.write_text(
        text.replace("duration = 0.3", "duration = 0.01").replace(
            '"../geometry/', f'"{ROOT / "geometry"}/'
        )
    )
    run = tmp_path / "run"
    assert main(["run", str(case), "-o", str(run), "--quiet"]) == 0
    assert main(["render", str(run), "-o", str(tmp_path / "frame.png")]) == 0
    assert (tmp_path / "frame.png").stat().st_size > 10_000
