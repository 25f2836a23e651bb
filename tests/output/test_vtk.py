"""perga.output.vtk: every file read back by meshio and pyvista equals what the simulation held
when it was recorded. Values are compared exactly (float64 written, float64 read) except the
soft overlaps, recomputed here by an independent formula (1e-12 m: round-off of two ways of
computing a point-segment distance on ~0.1 m coordinates), and the machine's outlines, which
the writer poses from the frame (hinge and axis angle, SI) and the test from Pymunk's bodies
(internal units): 1e-15 m, a few ulp of 0.1 m coordinates."""

from __future__ import annotations

import ast
import dataclasses
import gc
import json
import os
import subprocess
import sys
import tracemalloc
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import meshio
import numpy as np
import pytest
import pyvista as pv

import perga
from perga.case import load_case
from perga.contact.soft.polygon_set import HIST_ACTIVE
from perga.engine import Simulation
from perga.machine import units as u
from perga.model import ContactSpec
from perga.model.compile import compile_case
from perga.model.system import System
from perga.output.vtk import (
    CHAMBER_SEGMENTS,
    ROTOR_SIDES,
    SCRATCH_COLUMNS,
    PvdSeries,
    VtkRecorder,
)
from perga.run import prepare_directory, run_case

CASES = Path(__file__).parents[2] / "cases"
FRAMES = 12
STEPS_PER_FRAME = {"rigid": 1, "soft": 5}


@dataclass
class Frame:
    """What the simulation held when a frame was recorded (SI)."""

    time: float
    positions: np.ndarray
    velocities: np.ndarray
    angular_velocities: np.ndarray
    hammer_vertices: list[np.ndarray]
    swing_angles: np.ndarray
    hammer_spin: np.ndarray
    hinge_force: np.ndarray
    rotor_angle: float
    rotor_spin: float
    impacts: np.ndarray
    soft: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass
class Run:
    sim: Simulation
    directory: Path
    frames: list[Frame]
    pvd_after_record: list[list[tuple[float, str]]]


def spec_near_hammer(soft: bool) -> System:
    """The single-granule case with the granule 0.5 mm ahead of the hammer's leading face (so it
    is struck within the first frames) and, for soft contacts, a second granule overlapping it by
    0.1 mm (granule pairs on)."""
    name = "soft-single-granule" if soft else "single-granule"
    spec = compile_case(load_case(CASES / f"{name}.toml"))
    g = spec.granules[0]
    granules = [dataclasses.replace(g, position=(0.11, 0.0125 + 0.0005))]
    if not soft:
        return dataclasses.replace(spec, granules=tuple(granules))
    granules.append(dataclasses.replace(g, position=(0.11 + 2 * g.radius - 1e-4, 0.013)))
    pair = ContactSpec(g.material, g.material, 0.7, 0.35, spec.contacts[0].stiffness)
    return dataclasses.replace(
        spec, granules=tuple(granules), contacts=(*spec.contacts, pair), granule_collisions=True
    )


def hinge_forces(sim: Simulation) -> np.ndarray:
    joint_of = {j.b: j for j in sim.machine.hinges}
    return np.array(
        [
            joint_of[b].impulse * u.IMPULSE / sim.dt if b in joint_of else 0.0
            for b in sim.machine.hammer_bodies
        ]
    )


def point_polygon_distance(p: np.ndarray, vertices: np.ndarray) -> float:
    """Distance (m) from p to the boundary of a polygon that does not contain p."""
    a, b = vertices, np.roll(vertices, -1, axis=0)
    e = b - a
    t = np.clip(np.sum((p - a) * e, axis=1) / np.sum(e * e, axis=1), 0.0, 1.0)
    return float(np.min(np.linalg.norm(p - (a + t[:, None] * e), axis=1)))


def soft_expected(sim: Simulation) -> dict[str, np.ndarray]:
    """Contacts and largest overlap per granule by brute force over pairs, walls and hammers."""
    g = sim.contacts.granules
    contacts, overlap = np.zeros(g.n, dtype=int), np.zeros(g.n)
    for i in range(g.n):
        for j in range(g.n):
            delta = g.r[i] + g.r[j] - np.linalg.norm(g.x[i] - g.x[j])
            if i != j and delta > 0:
                contacts[i] += 1
                overlap[i] = max(overlap[i], delta)
        wall = g.r[i] + np.linalg.norm(g.x[i]) - sim.spec.chamber.radius
        if wall > 0:
            contacts[i] += 1
            overlap[i] = max(overlap[i], wall)
        polys = g.polygons
        for k in range(polys.n_poly):
            if g.polygon_hist[i, k, HIST_ACTIVE]:
                verts = polys.vertices[polys.start[k] : polys.start[k + 1]]
                contacts[i] += 1
                overlap[i] = max(overlap[i], g.r[i] - point_polygon_distance(g.x[i], verts))
    return {"contacts": contacts, "overlap_max": overlap}


def read_pvd(path: Path) -> list[tuple[float, str]]:
    """(timestep, file) of every DataSet of a .pvd, checking that each file exists."""
    root = ET.parse(path).getroot()
    assert root.get("type") == "Collection"
    entries = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
    assert all((path.parent / f).is_file() for _, f in entries)
    return entries


def snapshot(sim: Simulation) -> Frame:
    machine = sim.machine
    counts = np.bincount([i.granule for i in sim.impacts], minlength=len(sim.spec.granules))
    return Frame(
        time=sim.time,
        positions=sim.frame().granules.positions,
        velocities=sim.frame().granules.velocities,
        angular_velocities=sim.frame().granules.angular_velocities,
        hammer_vertices=[
            np.array([tuple(b.local_to_world(v)) for v in outline]) * u.LENGTH
            for b, outline in zip(machine.hammer_bodies, machine.hammer_outlines, strict=True)
        ],
        swing_angles=sim.frame().machine.swing_angles,
        hammer_spin=sim.frame().machine.angular_velocities,
        hinge_force=hinge_forces(sim),
        rotor_angle=sim.frame().machine.rotor_angle,
        rotor_spin=sim.frame().machine.rotor_angular_velocity,
        impacts=counts,
        soft=soft_expected(sim) if sim.spec.contact_model.kind != "rigid" else {},
    )


def simulate(directory: Path, kind: str) -> Run:
    spec = spec_near_hammer(kind == "soft")
    sim = Simulation(spec)
    recorder = VtkRecorder(directory, spec)
    frames, pvds = [], []
    for k in range(FRAMES):
        if k:
            for _ in range(STEPS_PER_FRAME[kind]):
                sim.step()
        frames.append(snapshot(sim))
        recorder.record(sim.frame(), sim.events())
        pvds.append(read_pvd(directory / "vtk" / "granules.pvd"))
        for part in ("hammers", "rotor"):
            assert read_pvd(directory / "vtk" / f"{part}.pvd") == [
                (t, f.replace("granules", part)) for t, f in pvds[-1]
            ]
    recorder.close()
    return Run(sim, directory / "vtk", frames, pvds)


@pytest.fixture(scope="module", params=["rigid", "soft"])
def run(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Run:
    return simulate(tmp_path_factory.mktemp(request.param), request.param)


def both(path: Path) -> tuple[meshio.Mesh, pv.UnstructuredGrid]:
    return meshio.read(path), pv.read(path)


def test_pvd_is_valid_after_every_record(run: Run) -> None:
    for k, entries in enumerate(run.pvd_after_record):
        assert (
            entries
            == [(f.time, f"granules_{j:06d}.vtu") for j, f in enumerate(run.frames)][: k + 1]
        )


def test_pvd_lists_times_in_order(run: Run) -> None:
    entries = read_pvd(run.directory / "granules.pvd")
    assert [t for t, _ in entries] == [f.time for f in run.frames]
    assert [t for t, _ in entries] == sorted(t for t, _ in entries)
    assert len(entries) == FRAMES


def test_granule_frames_round_trip(run: Run) -> None:
    spec = run.sim.spec
    radius = np.array([g.radius for g in spec.granules])
    mass = np.array([g.mass for g in spec.granules])
    moment = np.array([g.moment for g in spec.granules])
    for (_, file), frame in zip(read_pvd(run.directory / "granules.pvd"), run.frames, strict=True):
        m, p = both(run.directory / file)
        speed = np.hypot(frame.velocities[:, 0], frame.velocities[:, 1])
        w = frame.angular_velocities
        expected = {
            "radius": radius,
            "velocity": np.column_stack((frame.velocities, np.zeros(len(w)))),
            "speed": speed,
            "angular_velocity": w,
            "kinetic_energy": 0.5 * mass * speed**2 + 0.5 * moment * w**2,
            "id": np.arange(len(w)),
            "material": np.zeros(len(w)),
            "impacts": frame.impacts,
            **frame.soft,
        }
        points = np.column_stack((frame.positions, np.zeros(len(w))))
        np.testing.assert_array_equal(m.points, points)
        np.testing.assert_array_equal(p.points, points)
        assert [c.type for c in m.cells] == ["vertex"]
        np.testing.assert_array_equal(m.cells[0].data.ravel(), np.arange(len(w)))
        assert set(p.celltypes) == {pv.CellType.VERTEX}
        assert set(m.point_data) == set(p.point_data) == set(expected)
        for name, value in expected.items():
            if name == "overlap_max":
                np.testing.assert_allclose(m.point_data[name], value, rtol=0, atol=1e-12)
                np.testing.assert_array_equal(p.point_data[name], m.point_data[name])
            else:
                np.testing.assert_array_equal(m.point_data[name], value, err_msg=name)
                np.testing.assert_array_equal(p.point_data[name], value, err_msg=name)
    assert "material: 0 = beebread" in (run.directory / "granules.pvd").read_text()


def test_scene_is_exercised(run: Run) -> None:
    """The checks above see an impact and, for soft contacts, pair and hammer contacts."""
    assert run.frames[-1].impacts.sum() >= 1
    if run.frames[0].soft:
        assert run.frames[0].soft["contacts"].tolist() == [1, 1]  # the overlapping pair
        r = run.sim.contacts.granules.r
        apart = [np.linalg.norm(f.positions[0] - f.positions[1]) > r[0] + r[1] for f in run.frames]
        hammer = [
            a and f.soft["overlap_max"].min() > 0 for a, f in zip(apart, run.frames, strict=True)
        ]
        assert any(hammer)  # both granules on the hammer, not on each other


def _check_polygons(file: Path, outlines: list[np.ndarray], expected: dict[str, list]) -> None:
    """``file`` (read by meshio and pyvista) holds ``outlines`` as polygons with ``expected``
    cell data, exactly."""
    m, p = both(file)
    assert p.n_cells == len(outlines)
    for k, outline in enumerate(outlines):
        cell = p.get_cell(k)
        assert cell.type == pv.CellType.POLYGON
        np.testing.assert_allclose(p.points[cell.point_ids, :2], outline, rtol=0, atol=1e-15)
    flat = np.concatenate([c.data.ravel() for c in m.cells])
    np.testing.assert_array_equal(
        m.points[flat],
        p.points[np.concatenate([p.get_cell(k).point_ids for k in range(len(outlines))])],
    )
    assert sorted(p.cell_data.keys()) == sorted(expected)
    for name, value in expected.items():
        np.testing.assert_array_equal(p.cell_data[name], value, err_msg=name)
        np.testing.assert_array_equal(np.concatenate(m.cell_data[name]), value, err_msg=name)


def test_hammer_and_rotor_frames_round_trip(run: Run) -> None:
    """Each frame's hammers (hammers.pvd) and rotor disc (rotor.pvd), in series of their own,
    posed as the simulation has them."""
    spec = run.sim.spec
    hammers, rotors = read_pvd(run.directory / "hammers.pvd"), read_pvd(run.directory / "rotor.pvd")
    for (_, h), (_, r), frame in zip(hammers, rotors, run.frames, strict=True):
        theta = frame.rotor_angle
        n = len(frame.swing_angles)
        mounts = np.array([h.angle_on_rotor for h in spec.hammers])
        _check_polygons(
            run.directory / h,
            frame.hammer_vertices,
            {
                "id": [*range(n)],
                "swing_angle": [*frame.swing_angles],
                "angle": [*(theta + mounts + frame.swing_angles)],
                "angular_velocity": [*frame.hammer_spin],
                "hinge_force": [*frame.hinge_force],
            },
        )
        phi = theta + 2 * np.pi * np.arange(ROTOR_SIDES) / ROTOR_SIDES
        disc = spec.rotor.radius * np.column_stack((np.cos(phi), np.sin(phi)))
        _check_polygons(
            run.directory / r, [disc], {"angle": [theta], "angular_velocity": [frame.rotor_spin]}
        )
    assert any(f.hinge_force[0] > 0 for f in run.frames[1:])


def test_chamber_written_once(run: Run) -> None:
    m, p = both(run.directory / "chamber.vtu")
    np.testing.assert_allclose(
        np.hypot(p.points[:, 0], p.points[:, 1]), run.sim.spec.chamber.radius, rtol=1e-15
    )
    assert p.n_points == CHAMBER_SEGMENTS and p.n_cells == 1
    ids = p.get_cell(0).point_ids
    assert ids[0] == ids[-1] and len(ids) == CHAMBER_SEGMENTS + 1
    np.testing.assert_array_equal(m.points, p.points)


def test_trajectories_round_trip(run: Run) -> None:
    m, p = both(run.directory / "trajectories.vtu")
    n = len(run.frames[0].positions)
    assert p.n_cells == n
    for g in range(n):
        cell = p.get_cell(g)
        assert cell.type == pv.CellType.POLY_LINE
        track = np.array([f.positions[g] for f in run.frames])
        np.testing.assert_array_equal(p.points[cell.point_ids, :2], track)
        np.testing.assert_array_equal(m.points[cell.point_ids, :2], track)
        speed = [np.hypot(*f.velocities[g]) for f in run.frames]
        for mesh in (m, p):
            np.testing.assert_array_equal(
                mesh.point_data["time"][cell.point_ids], [f.time for f in run.frames]
            )
            np.testing.assert_array_equal(mesh.point_data["speed"][cell.point_ids], speed)
    np.testing.assert_array_equal(p.cell_data["id"], np.arange(n))


def test_impacts_round_trip(run: Run) -> None:
    impacts = run.sim.impacts
    m, p = both(run.directory / "impacts.vtu")
    for mesh in (m, p):
        np.testing.assert_array_equal(mesh.points[:, :2], [i.point for i in impacts])
        for name in (
            "time",
            "normal_impulse",
            "granule_energy_gain",
            "dissipated",
            "granule",
            "hammer",
        ):
            np.testing.assert_array_equal(
                mesh.point_data[name], [getattr(i, name) for i in impacts]
            )
        np.testing.assert_array_equal(mesh.point_data["normal"][:, :2], [i.normal for i in impacts])
    assert set(p.celltypes) == {pv.CellType.VERTEX}


def test_no_impacts_leaves_an_empty_readable_file(tmp_path: Path) -> None:
    spec = compile_case(load_case(CASES / "single-granule.toml"))
    sim = Simulation(spec)
    recorder = VtkRecorder(tmp_path, sim.spec)
    recorder.record(sim.frame(), sim.events())
    recorder.close()
    recorder.close()  # idempotent
    impacts = pv.read(tmp_path / "vtk" / "impacts.vtu")
    assert impacts.n_points == 0
    assert "normal_impulse" in impacts.point_data
    assert pv.read(tmp_path / "vtk" / "trajectories.vtu").n_cells == 1


def test_trajectories_identical_to_the_in_memory_build(run: Run) -> None:
    """The streamed file holds exactly (same float64 bits, same cells) what a build from every
    frame's positions and speeds held in memory holds (built here with pyvista, not perga's
    writer): the points frame by frame, each granule's line through its own."""
    frames, n = len(run.frames), len(run.frames[0].positions)
    track = np.concatenate([f.positions for f in run.frames])
    cells = np.concatenate([np.r_[frames, np.arange(k, frames * n, n)] for k in range(n)])
    points = np.column_stack((track, np.zeros(len(track))))
    reference = pv.UnstructuredGrid(cells, np.full(n, pv.CellType.POLY_LINE, np.uint8), points)
    speeds = [np.hypot(f.velocities[:, 0], f.velocities[:, 1]) for f in run.frames]
    expected_point_data = {
        "time": np.repeat(np.array([f.time for f in run.frames]), n),
        "speed": np.concatenate(speeds),
    }
    written = pv.read(run.directory / "trajectories.vtu")
    assert np.array_equal(written.points, reference.points)
    assert np.array_equal(written.cells, reference.cells)
    assert np.array_equal(written.celltypes, reference.celltypes)
    for name, values in expected_point_data.items():
        assert np.array_equal(written.point_data[name], values), name
    assert np.array_equal(written.cell_data["id"], np.arange(n))
    assert not (run.directory / ".trajectories.f8").exists()
    assert not list(run.directory.glob(".trajectories-*"))


def held_bytes(recorder: VtkRecorder) -> int:
    """Bytes of the numpy arrays the recorder holds (in its attributes, their lists, tuples and
    dicts, and its series' attributes)."""
    total, seen = 0, set()
    stack: list[object] = [vars(recorder)]
    while stack:
        item = stack.pop()
        if id(item) in seen:
            continue
        seen.add(id(item))
        if isinstance(item, np.ndarray):
            total += item.nbytes
        elif isinstance(item, dict):
            stack += item.values()
        elif isinstance(item, list | tuple):
            stack += item
        elif isinstance(item, PvdSeries):
            stack.append(vars(item))
    return total


@pytest.mark.slow  # 125 frames of 3,000 granules in a process of its own: 13-27 s
def test_recorder_memory_does_not_grow_with_frames(tmp_path: Path) -> None:
    """3,000 granules (the separator's 300, ten times over; never stepped): the arrays held are
    the same after 5 and 125 frames; over the last 60 frames the Python allocations made under
    perga's code (a traceback through the package, garbage collected) grow by less than 5 % of
    the 4.3 MB that holding their positions and speeds would take (what grows is the .pvd
    lists, 0.6-1.7 kB a frame whatever the granules: 66 kB in all, measured); the scratch file
    holds every frame and is gone after close. Measured in a process of its own: in a fresh
    clone's whole default run, 7.8 MB appeared in that window under perga's code, never in a
    part of the suite nor alone; why is not found (docs/dev/reliability.md)."""
    if os.environ.get("PERGA_MEMORY_PROBE") != "1":
        probe = f"{__file__}::test_recorder_memory_does_not_grow_with_frames"
        result = subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-m", "slow", probe],
            env={**os.environ, "PERGA_MEMORY_PROBE": "1"}, capture_output=True, text=True,
            timeout=600,
        )  # fmt: skip
        assert result.returncode == 0, result.stdout[-3000:]
        return

    spec = compile_case(load_case(CASES / "separator.toml"))
    spec = dataclasses.replace(spec, granules=spec.granules * 10)
    sim = Simulation(spec)
    n = len(spec.granules)
    recorder = VtkRecorder(tmp_path, sim.spec)
    for _ in range(5):
        recorder.record(sim.frame(), sim.events())
    held = held_bytes(recorder)
    for _ in range(60):
        recorder.record(sim.frame(), sim.events())
    ours = [tracemalloc.Filter(True, f"{Path(perga.__file__).parent}/*", all_frames=True)]
    tracemalloc.start(64)  # deep enough to reach the test's frame from numpy's
    gc.collect()
    before = tracemalloc.take_snapshot().filter_traces(ours)
    for _ in range(60):
        recorder.record(sim.frame(), sim.events())
    gc.collect()
    after = tracemalloc.take_snapshot().filter_traces(ours)
    tracemalloc.stop()
    grown = sum(stat.size_diff for stat in after.compare_to(before, "filename"))
    assert held_bytes(recorder) == held
    assert held < 100 * n * 8  # a few per-granule arrays
    assert grown < 0.05 * 60 * n * 3 * 8, grown
    scratch = tmp_path / "vtk" / ".trajectories.f8"
    assert scratch.stat().st_size == 125 * n * SCRATCH_COLUMNS * 8
    recorder.close()
    assert not scratch.exists()
    trajectories = pv.read(tmp_path / "vtk" / "trajectories.vtu")
    assert trajectories.n_points == 125 * n and trajectories.n_cells == n


def test_interrupted_run_gets_its_trajectories(tmp_path: Path) -> None:
    """The runner's close() in finally builds trajectories.vtu from the frames written, and
    keeps the scratch file it is built from: a resumed run goes on with it."""
    text = (CASES / "single-granule.toml").read_text()
    path = tmp_path / "case.toml"
    path.write_text(text.replace("every = 2e-4", "every = 1e-3"))
    out = tmp_path / "run"
    prepare_directory(out, overwrite=False)

    def interrupt(t: float, _duration: float, _steps: int) -> None:
        if t > 0.01:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_case(load_case(path), path, out, interrupt)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    trajectories = pv.read(out / "vtk" / "trajectories.vtu")
    assert trajectories.n_points == summary["frames"] == len(read_pvd(out / "vtk" / "granules.pvd"))
    assert summary["frames"] >= 11
    assert (out / "vtk" / ".trajectories.f8").exists()


def test_the_paraview_state_names_the_series_and_the_top_speed(run: Run) -> None:
    """paraview_state.py (opened in real ParaView by tests/output/test_paraview.py): the scene
    script and a call on the series beside it, coloured up to the run's top speed, no path of
    this machine in it (two runs of a case write the same bytes)."""
    text = (run.directory / "paraview_state.py").read_text()
    tree = ast.parse(text)
    call = tree.body[-1].value
    assert isinstance(call, ast.Call) and call.func.id == "show_run"
    assert ast.unparse(call.args[0]) == "Path(__file__).resolve().parent"
    keywords = {k.arg: ast.literal_eval(k.value) for k in call.keywords}
    top = max(float(np.hypot(*f.velocities.T).max()) for f in run.frames)
    assert keywords == {"speed_max": top, "chamber": True}
    assert str(run.directory) not in text and "/tmp" not in text
    for name in ("granules.pvd", "hammers.pvd", "rotor.pvd", "chamber.vtu"):
        assert f'"{name}"' in text and (run.directory / name).exists()
