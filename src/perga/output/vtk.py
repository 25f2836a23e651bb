"""ParaView output: binary, zlib-compressed ``.vtu`` files written by VTK (through pyvista) and
``.pvd`` collections whose ``timestep`` is simulated time, s (design notes, section 6).

Files in ``RUN/vtk/`` (SI units; z = 0 everywhere):

* ``granules.pvd`` + ``granules_NNNNNN.vtu``, one per frame: a point per granule with a
  VTK_VERTEX cell; point data ``radius`` (m), ``velocity`` (m/s, 3 components), ``speed``
  (m/s), ``angular_velocity`` (rad/s), ``kinetic_energy`` (½mv² + ½Iω², J), ``id`` (index in
  the spec), ``material`` (index into the sorted granule material names, listed in a comment of
  ``granules.pvd``), ``impacts`` (granule-hammer impacts so far); with soft contacts also
  ``contacts`` (granule, wall and hammer contacts now: overlap > 0, hammers by the kernel's
  active flag) and ``overlap_max`` (largest of those overlaps, m; 0 without contact).
* ``machine.pvd`` + ``machine_NNNNNN.vtu``, one per frame: each hammer as a VTK_POLYGON posed at
  the frame, then the rotor disc (its outline from the rotor's file, or a 64-gon of the rotor
  radius); cell data ``id`` (hammer index,
  −1 for the rotor), ``swing_angle`` (α, rad; 0 for the rotor), ``angle`` (absolute orientation:
  rotor angle + angle on the rotor + α, rad), ``angular_velocity`` (rad/s), ``hinge_force``
  (magnitude of the hinge reaction over the last Pymunk step, N; 0 for welded and free hammers
  and the rotor).
* ``chamber.vtu``: the wall's inner outline (from the chamber's file, or its circle as 256
  segments) as one closed VTK_POLY_LINE, written at the first frame (absent without a chamber).
* ``trajectories.vtu`` (at ``close``): one VTK_POLY_LINE per granule through its recorded frame
  positions; point data ``time`` (s) and ``speed`` (m/s), cell data ``id``. Each frame's time,
  positions and speeds are appended to the scratch file ``.trajectories.f8`` (raw float64,
  flushed every frame) rather than kept in memory, so the recorder holds O(granules) whatever
  the number of frames; ``close`` (called by the runner whatever ended the run) builds the file
  from it, in blocks of frames, and deletes it. Building needs the file's arrays in memory
  once (~56 B per granule and frame).
* ``impacts.vtu`` (at ``close``): a VTK_VERTEX per granule-hammer impact at its contact point;
  point data ``time`` (s), ``granule``, ``hammer``, ``normal_impulse`` (N·s),
  ``granule_energy_gain`` (J), ``dissipated`` (J), ``normal`` (3 components). With no impacts
  the file has no points (ParaView and pyvista read it; meshio 5.3 cannot read empty arrays).

With ``output.vtk_3d`` (a :class:`~perga.model.spec.DrawingSpec` in the scene spec) also
``machine3d.pvd`` and ``chamber3d.vtu``, and point data ``thickness`` (m) in the granule
frames: see :mod:`perga.output.vtk3d`.

Each ``.pvd`` is rewritten atomically (temporary file, then ``os.replace``) after every frame,
so a run stopped at any point leaves valid collections of the frames written so far.
"""

from __future__ import annotations

import itertools
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import BinaryIO

import numpy as np
import pymunk
import pyvista as pv
from numpy.typing import NDArray

from perga.contact.soft.model import SoftSimulation
from perga.contact.soft.polygon_set import HIST_ACTIVE
from perga.engine import units as u
from perga.engine.simulation import FloatArray, Simulation
from perga.geometry.disc_polygon import closest_feature
from perga.geometry.polygon import outline_or_circle
from perga.model.spec import RotorSpec
from perga.output import vtk3d

ROTOR_SIDES = 64
"""Sides of the polygon drawn for the rotor disc."""
CHAMBER_SEGMENTS = 256
"""Segments of the polyline drawn for the chamber's inner circle."""
TRAJECTORY_BLOCK = 1 << 22
"""Values (float64) of the trajectory scratch read at a time by ``close``: 32 MiB."""


class PvdSeries:
    """A ``NAME.pvd`` collection of ``NAME_NNNNNN.vtu`` frames in ``directory``; ``comment`` is
    written as an XML comment in the index."""

    def __init__(self, directory: Path, name: str, comment: str = "") -> None:
        self.directory = directory
        self.name = name
        self.comment = comment
        self.entries: list[tuple[float, str]] = []

    @property
    def path(self) -> Path:
        """The ``.pvd`` file."""
        return self.directory / f"{self.name}.pvd"

    def add(self, time: float, mesh: pv.DataSet) -> None:
        """Write ``mesh`` as the frame at ``time`` (s), then rewrite the index atomically."""
        file = f"{self.name}_{len(self.entries):06d}.vtu"
        mesh.save(self.directory / file, binary=True, compression="zlib")
        self.entries.append((time, file))
        root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
        if self.comment:
            root.append(ET.Comment(f" {self.comment} "))
        collection = ET.SubElement(root, "Collection")
        for t, f in self.entries:
            ET.SubElement(collection, "DataSet", timestep=repr(t), group="", part="0", file=f)
        ET.indent(root)
        temporary = self.path.with_suffix(".pvd.tmp")
        ET.ElementTree(root).write(temporary, encoding="utf-8", xml_declaration=True)
        os.replace(temporary, self.path)


def _grid(
    cells: list[NDArray[np.int64]], cell_type: int, points: FloatArray
) -> pv.UnstructuredGrid:
    """Cells of one type, each a list of point indices, over 2-D ``points`` (m) lifted to z = 0."""
    flat = np.concatenate([np.concatenate(([len(c)], c)) for c in cells]) if cells else []
    return pv.UnstructuredGrid(
        np.asarray(flat, dtype=np.int64),
        np.full(len(cells), cell_type, dtype=np.uint8),
        _lift(points),
    )


def _lift(points: FloatArray) -> FloatArray:
    """(n, 2) -> (n, 3) with z = 0."""
    out = np.zeros((len(points), 3))
    out[:, :2] = points
    return out


def _vertices(n: int, points: FloatArray) -> pv.UnstructuredGrid:
    """``n`` points (m), each with its own VTK_VERTEX cell."""
    cells = np.column_stack((np.ones(n, dtype=np.int64), np.arange(n, dtype=np.int64)))
    return pv.UnstructuredGrid(
        cells.ravel(), np.full(n, pv.CellType.VERTEX, dtype=np.uint8), _lift(points)
    )


def soft_contacts(sim: SoftSimulation) -> tuple[NDArray[np.int32], FloatArray]:
    """Per granule: the number of contacts now (granule pairs and walls with overlap > 0,
    hammers whose contact the kernel holds active) and the largest of their overlaps, m."""
    g = sim.granules
    n = g.n
    i, j, delta, _ = g._pairs()
    count = np.bincount(i, minlength=n) + np.bincount(j, minlength=n)
    overlap = np.zeros(n)
    np.maximum.at(overlap, i, delta)
    np.maximum.at(overlap, j, delta)
    walls = g._walls_overlap()
    count += np.count_nonzero(walls > 0.0, axis=1)
    if walls.size:
        np.maximum(overlap, walls.max(axis=1), out=overlap)
    active = g.polygon_hist[:, :, HIST_ACTIVE] != 0.0
    count += np.count_nonzero(active, axis=1)
    polys = g._poly[0].outline()
    for a, k in np.argwhere(active):
        d, _, _ = closest_feature(g.x[a, 0], g.x[a, 1], *polys, k)
        overlap[a] = max(overlap[a], g.r[a] - d)
    return count.astype(np.int32), overlap


class VtkRecorder:
    """Writes the files listed in the module doc into ``directory / "vtk"``: ``record(sim)``
    a frame at ``sim.time``, ``close()`` the trajectories and impacts (idempotent)."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory / "vtk"
        self.directory.mkdir(parents=True, exist_ok=True)
        self.granules = PvdSeries(self.directory, "granules")
        self.machine = PvdSeries(self.directory, "machine")
        self.machine3d: PvdSeries | None = None
        self._machine3d: vtk3d.Machine3D | None = None
        self.frames = 0
        self.scratch = self.directory / ".trajectories.f8"
        self._scratch: BinaryIO | None = None
        self._sim: Simulation | None = None
        self._radius = self._mass = self._moment = np.empty(0)
        self._material = np.empty(0, dtype=np.int32)
        self._impact_count = np.empty(0, dtype=np.int64)
        self._impacts_counted = 0
        self._closed = False

    def _start(self, sim: Simulation) -> None:
        """Constant per-granule arrays, material names and the chamber, at the first frame."""
        spec = sim.scene.spec
        names = sorted({g.material for g in spec.granules})
        self._radius = np.array([g.radius for g in spec.granules], dtype=float)
        self._mass = np.array([g.mass for g in spec.granules], dtype=float)
        self._moment = np.array([g.moment if g.rolls else 0.0 for g in spec.granules])
        self._material = np.array([names.index(g.material) for g in spec.granules], dtype=np.int32)
        self._impact_count = np.zeros(len(spec.granules), dtype=np.int64)
        self._scratch = open(self.scratch, "wb")  # noqa: SIM115 (closed by close())
        self.granules.comment = "material: " + ", ".join(
            f"{k} = {name}" for k, name in enumerate(names)
        )
        if spec.chamber is not None:
            c = spec.chamber
            wall = outline_or_circle(c.outline, c.radius, CHAMBER_SEGMENTS)
            ring = np.append(np.arange(len(wall)), 0)
            chamber = _grid([ring], pv.CellType.POLY_LINE, wall)
            chamber.save(self.directory / "chamber.vtu", binary=True, compression="zlib")
        if spec.drawing is not None:
            self._start_3d(sim)

    def _start_3d(self, sim: Simulation) -> None:
        """The extruded parts, the ``machine3d`` series and ``chamber3d.vtu``."""
        scene, spec = sim.scene, sim.scene.spec
        drawing = spec.drawing
        assert drawing is not None
        outlines = [np.asarray(o, dtype=float) * u.LENGTH for o in scene.hammer_outlines]
        outlines.append(_disc(spec.rotor))
        self._machine3d = vtk3d.Machine3D(
            [*scene.hammer_bodies, scene.rotor],
            outlines,
            [*drawing.hammer_thickness, drawing.rotor_thickness],
        )
        self.machine3d = PvdSeries(self.directory, "machine3d")
        if spec.chamber is not None:
            c = spec.chamber
            inner = outline_or_circle(c.outline, c.radius, CHAMBER_SEGMENTS)
            part = vtk3d.wall(inner, c.wall_thickness, drawing.chamber_height)
            chamber = vtk3d.part_grid(part)
            chamber.save(self.directory / "chamber3d.vtu", binary=True, compression="zlib")

    def record(self, sim: Simulation) -> None:
        """Write the granule and machine frames at ``sim.time`` and update both ``.pvd``."""
        if self._sim is None:
            self._start(sim)
        self._sim = sim
        t = sim.time
        p, v, w = (
            sim.granule_positions(),
            sim.granule_velocities(),
            sim.granule_angular_velocities(),
        )
        speed = np.hypot(v[:, 0], v[:, 1])
        new = sim.impacts[self._impacts_counted :]
        for impact in new:
            self._impact_count[impact.granule] += 1
        self._impacts_counted += len(new)

        mesh = _vertices(len(p), p)
        data = mesh.point_data
        data["radius"] = self._radius
        data["velocity"] = _lift(v)
        data["speed"] = speed
        data["angular_velocity"] = w
        data["kinetic_energy"] = 0.5 * self._mass * speed**2 + 0.5 * self._moment * w**2
        data["id"] = np.arange(len(p), dtype=np.int64)
        data["material"] = self._material
        data["impacts"] = self._impact_count
        if isinstance(sim, SoftSimulation):
            data["contacts"], data["overlap_max"] = soft_contacts(sim)
        drawing = sim.scene.spec.drawing
        if drawing is not None:
            data["thickness"] = np.full(len(p), drawing.granule_thickness)
        self.granules.add(t, mesh)
        cell_data = machine_cell_data(sim)
        self.machine.add(t, machine_mesh(sim, cell_data))
        if self.machine3d is not None and self._machine3d is not None:
            self.machine3d.add(t, self._machine3d.mesh(cell_data))
        row = np.empty((len(p), 3))
        row[:, :2], row[:, 2] = p, speed
        assert self._scratch is not None
        self._scratch.write(np.float64(t).tobytes())
        self._scratch.write(row.tobytes())
        self._scratch.flush()
        self.frames += 1

    def close(self) -> None:
        """Write ``trajectories.vtu`` and ``impacts.vtu`` (nothing if no frame was recorded)."""
        if self._closed or self._sim is None:
            return
        self._closed = True
        try:
            self._write_trajectories()
        finally:
            self.scratch.unlink(missing_ok=True)
        self._write_impacts(self._sim)

    def _write_trajectories(self) -> None:
        """``trajectories.vtu`` from the scratch file (frame-major) read in blocks of frames."""
        assert self._scratch is not None
        self._scratch.close()
        frames, n = self.frames, len(self._radius)
        scratch = np.memmap(self.scratch, dtype=np.float64, mode="r", shape=(frames, 1 + 3 * n))
        points = np.zeros((n, frames, 3))  # granule-major
        speed = np.empty((n, frames))
        block = max(1, TRAJECTORY_BLOCK // (1 + 3 * n))
        for a in range(0, frames, block):
            rows = np.asarray(scratch[a : a + block, 1:])
            rows = rows.reshape(len(rows), n, 3)
            points[:, a : a + len(rows), :2] = rows[:, :, :2].transpose(1, 0, 2)
            speed[:, a : a + len(rows)] = rows[:, :, 2].T
        times = np.array(scratch[:, 0])
        del scratch
        cells = np.empty((n, frames + 1), dtype=np.int64)
        cells[:, 0] = frames
        cells[:, 1:] = np.arange(n * frames, dtype=np.int64).reshape(n, frames)
        trajectories = pv.UnstructuredGrid(
            cells.ravel(),
            np.full(n, pv.CellType.POLY_LINE, dtype=np.uint8),
            points.reshape(-1, 3),
            deep=False,
        )
        del cells
        trajectories.point_data["time"] = np.tile(times, n)
        trajectories.point_data["speed"] = speed.reshape(-1)
        trajectories.cell_data["id"] = np.arange(n, dtype=np.int64)
        trajectories.save(self.directory / "trajectories.vtu", binary=True, compression="zlib")

    def _write_impacts(self, sim: Simulation) -> None:
        """``impacts.vtu``: every granule-hammer impact of the run."""
        impacts = sim.impacts
        points = np.array([i.point for i in impacts], dtype=float).reshape(-1, 2)
        mesh = _vertices(len(impacts), points)
        columns: dict[str, np.ndarray] = {
            name: np.array([getattr(i, name) for i in impacts], dtype=float)
            for name in ("time", "normal_impulse", "granule_energy_gain", "dissipated")
        }
        for name in ("granule", "hammer"):
            columns[name] = np.array([getattr(i, name) for i in impacts], dtype=np.int64)
        columns["normal"] = _lift(np.array([i.normal for i in impacts], dtype=float).reshape(-1, 2))
        for name, values in columns.items():
            # through VTK: pyvista refuses empty arrays, a run without impacts has them
            mesh.GetPointData().AddArray(pv.convert_array(values, name=name))
        mesh.save(self.directory / "impacts.vtu", binary=True, compression="zlib")


def _disc(rotor: RotorSpec) -> FloatArray:
    """The rotor disc's outline in the rotor's frame, m (a ``ROTOR_SIDES``-gon without one)."""
    return outline_or_circle(rotor.outline, rotor.radius, ROTOR_SIDES)


def machine_cell_data(sim: Simulation) -> dict[str, NDArray]:
    """Per part now, the hammers then the rotor: the cell data listed in the module doc."""
    scene = sim.scene
    hinges = {j.b: j for j in scene.joints if isinstance(j, pymunk.PivotJoint)}
    force = [
        0.0 if (joint := hinges.get(body)) is None else joint.impulse * u.IMPULSE / sim.dt
        for body in scene.hammer_bodies
    ]
    alpha = sim.hammer_swing_angles()
    mounts = np.array([h.angle_on_rotor for h in scene.spec.hammers], dtype=float)
    theta = sim.rotor_angle()
    return {
        "id": np.append(np.arange(len(alpha), dtype=np.int64), -1),
        "swing_angle": np.append(alpha, 0.0),
        "angle": np.append(theta + mounts + alpha, theta),
        "angular_velocity": np.append(
            sim.hammer_angular_velocities(), sim.rotor_angular_velocity()
        ),
        "hinge_force": np.append(force, 0.0),
    }


def machine_mesh(
    sim: Simulation, cell_data: dict[str, NDArray] | None = None
) -> pv.UnstructuredGrid:
    """The hammers posed now, then the rotor disc, as polygons with the cell data listed in the
    module doc (``cell_data``: :func:`machine_cell_data`, computed if not given)."""
    scene = sim.scene
    outlines: list[FloatArray] = [
        np.array([tuple(body.local_to_world(v)) for v in outline]) * u.LENGTH
        for body, outline in zip(scene.hammer_bodies, scene.hammer_outlines, strict=True)
    ]
    rotor = scene.rotor
    disc = _disc(scene.spec.rotor) / u.LENGTH
    outlines.append(np.array([tuple(rotor.local_to_world(tuple(v))) for v in disc]) * u.LENGTH)
    ends = np.cumsum([0] + [len(o) for o in outlines])
    cells = [np.arange(a, b, dtype=np.int64) for a, b in itertools.pairwise(ends)]
    mesh = _grid(cells, pv.CellType.POLYGON, np.concatenate(outlines))
    for name, values in (cell_data or machine_cell_data(sim)).items():
        mesh.cell_data[name] = values
    return mesh
