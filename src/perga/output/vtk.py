"""ParaView output: binary, zlib-compressed ``.vtu`` files (VTK's XML format,
:mod:`perga.output.vtk_grid`) and ``.pvd`` collections whose ``timestep`` is simulated time, s
(design notes, section 6).

Files in ``RUN/vtk/`` (SI units; z = 0 everywhere):

* ``granules.pvd`` + ``granules_NNNNNN.vtu``, one per frame: a point per granule with a
  VTK_VERTEX cell; point data ``radius`` (m), ``velocity`` (m/s, 3 components), ``speed``
  (m/s), ``angular_velocity`` (rad/s), ``kinetic_energy`` (½mv² + ½Iω², J), ``id`` (the
  granule's number for the whole run: granules fed later get the next ones, and a granule
  keeps its number when others leave), ``material`` (index into the sorted granule material
  names, listed in a comment of ``granules.pvd``), ``impacts`` (granule-hammer impacts so far);
  with held granules in the system ``held`` (1 while in its cell), with damage ``survival``
  (expected, -) and ``broken`` (1 if drawn broken); with soft contacts also ``contacts``
  (granule, wall and hammer contacts now: overlap > 0, hammers by the kernel's active flag) and
  ``overlap_max`` (largest of those overlaps, m; 0 without contact). The number of points
  changes from frame to frame when granules are fed or leave.
* ``hammers.pvd`` + ``hammers_NNNNNN.vtu``, one per frame: each hammer as a VTK_POLYGON posed
  at the frame; cell data ``id`` (hammer index), ``swing_angle`` (α, rad), ``angle`` (absolute
  orientation: rotor angle + angle on the rotor + α, rad), ``angular_velocity`` (rad/s),
  ``hinge_force`` (magnitude of the hinge reaction over the last Pymunk step, N; 0 for welded
  and free hammers).
* ``rotor.pvd`` + ``rotor_NNNNNN.vtu``, one per frame: the rotor disc as a VTK_POLYGON (its
  outline from the rotor's file, or a 64-gon of the rotor radius) turned to the frame's rotor
  angle; cell data ``angle`` (rad) and ``angular_velocity`` (rad/s). A series of its own, so
  that the opaque disc can be shown, hidden or drawn as an outline apart from the hammers.
* ``chamber.vtu``: the wall's inner outline (from the chamber's file, or its circle as 256
  segments) as one closed VTK_POLY_LINE, written at the first frame (absent without a chamber).
* ``trajectories.vtu`` (at ``close``): one VTK_POLY_LINE per granule (in the order of ids)
  through the frames it was present in; point data ``time`` (s) and ``speed`` (m/s), cell data
  ``id``. The points are in the order they were recorded, frame by frame, and each line lists
  its own. As each frame is recorded its points, times and speeds go on through a zlib stream
  each (:class:`~perga.output.vtk_grid.ArrayStream`, files ``.trajectories-NAME.z``) and its
  rows (time, id, x, y, speed) are appended to the scratch file ``.trajectories.f8`` (raw
  float64, flushed every frame), so the recorder holds O(granules) whatever the number of
  frames, and ``close`` (called by the runner whatever ended the run) only orders the points
  into lines (from the ids in the scratch file) and writes the file: it holds the compressed
  arrays and ~16 B per granule and frame, then deletes the scratch file. A recorder taken from
  a checkpoint rebuilds its streams from the scratch file.
* ``impacts.vtu`` (at ``close``): a VTK_VERTEX per granule-hammer impact at its contact point;
  point data ``time`` (s), ``granule`` (id), ``hammer``, ``normal_impulse`` (N·s),
  ``granule_energy_gain`` (J), ``dissipated`` (J), ``specific_energy`` (½v_n², J/kg),
  ``normal`` (3 components), with damage ``breakage_probability`` and ``survival``. With no
  impacts the file has no points (ParaView and pyvista read it; meshio 5.3 cannot read empty
  arrays).

With ``output.vtk_3d`` (a :class:`~perga.model.system.DrawingSpec` in the system) also
``hammers3d.pvd``, ``rotor3d.pvd`` and ``chamber3d.vtu``, and point data ``thickness`` (m) in
the granule frames: see :mod:`perga.output.vtk3d`.

``paraview_state.py`` (:mod:`perga.output.paraview_state`; written at the first frame and
again at ``close`` with the run's top speed): a ParaView Python state of these files, for File >
Load State or ``paraview --state=RUN/vtk/paraview_state.py``.

Each ``.pvd`` is extended after every frame by one write of the new entry and the closing tags
(:class:`PvdSeries`), so a run stopped at any point leaves valid collections of the frames
written so far.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import BinaryIO
from xml.sax.saxutils import escape

import numpy as np
from numpy.typing import NDArray

from perga.geometry.polygon import outline_or_circle
from perga.model.frame import Frame, MachineFrame
from perga.model.records import Events, Impact
from perga.model.system import System
from perga.output import paraview_state, vtk3d, vtk_grid
from perga.output.files import reopen_at
from perga.output.vtk_grid import POLY_LINE, POLYGON, ArrayStream, Grid

FloatArray = NDArray[np.float64]

ROTOR_SIDES = 64
"""Sides of the polygon drawn for the rotor disc."""
CHAMBER_SEGMENTS = 256
"""Segments of the polyline drawn for the chamber's inner circle."""
TRAJECTORY_BLOCK = 1 << 22
"""Values (float64) of the trajectory scratch read at a time to rebuild the streams: 32 MiB."""
SCRATCH_COLUMNS = 5
"""Values per granule and frame in the trajectory scratch: time, id, x, y, speed."""


_PVD_END = "  </Collection>\n</VTKFile>\n"
"""The closing tags of a ``.pvd`` index."""


class PvdSeries:
    """A ``NAME.pvd`` collection of ``NAME_NNNNNN.vtu`` frames in ``directory``; ``comment`` is
    written as an XML comment in the index (set it before the first frame).

    The index is a complete XML file after every frame: the first frame writes it whole; each
    later frame overwrites the closing tags with its entry and the closing tags, in one
    ``pwrite`` (one system call, which a killed process cannot leave half done). Rewriting the
    whole index through a temporary file and a rename, as before, created two files a frame;
    on this machine's file system a file creation costs about 1 ms (docs/dev/performance.md)."""

    def __init__(self, directory: Path, name: str, comment: str = "") -> None:
        self.directory = directory
        self.name = name
        self.comment = comment
        self.entries: list[tuple[float, str]] = []
        self._fd: int | None = None
        self._end = 0
        """Byte offset of the closing tags in the index."""

    def __getstate__(self) -> dict[str, object]:
        """The series as it stands (a checkpoint): its frames and the index's length."""
        return {k: v for k, v in self.__dict__.items() if k != "_fd"}

    def __setstate__(self, state: dict[str, object]) -> None:
        """Go on from a checkpoint: the index cut back to its frames then, with its closing
        tags, and the frames written after it removed."""
        self.__dict__.update(state)
        self._fd = None
        for frame in self.directory.glob(f"{self.name}_*.vtu"):
            if int(frame.stem.rpartition("_")[2]) >= len(self.entries):
                frame.unlink()
        if self.entries:
            self._fd = reopen_at(self.path, self._end)
            os.write(self._fd, _PVD_END.encode("utf-8"))

    @property
    def path(self) -> Path:
        """The ``.pvd`` file."""
        return self.directory / f"{self.name}.pvd"

    def add(self, time: float, mesh: Grid) -> None:
        """Write ``mesh`` as the frame at ``time`` (s), then add it to the index."""
        file = f"{self.name}_{len(self.entries):06d}.vtu"
        vtk_grid.save(mesh, self.directory / file)
        self.entries.append((time, file))
        entry = (
            f'    <DataSet timestep="{float(time)!r}" group="" part="0" file="{escape(file)}" />\n'
        ).encode()
        if self._fd is None:
            comment = f"  <!-- {self.comment} -->\n" if self.comment else ""
            head = (
                "<?xml version='1.0' encoding='utf-8'?>\n"
                '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                f"{comment}  <Collection>\n"
            ).encode()
            self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_TRUNC, 0o644)
            os.write(self._fd, head + entry + _PVD_END.encode("utf-8"))
            self._end = len(head) + len(entry)
            return
        try:
            os.pwrite(self._fd, entry + _PVD_END.encode("utf-8"), self._end)
        except OSError:  # the index as it was: its closing tags back, nothing after them
            end = _PVD_END.encode("utf-8")
            os.pwrite(self._fd, end, self._end)
            os.ftruncate(self._fd, self._end + len(end))
            raise
        self._end += len(entry)

    def close(self) -> None:
        """Close the index (idempotent); it is complete whether or not this is called."""
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None


def _polylines(lines: list[NDArray[np.int64]], points: FloatArray) -> Grid:
    """One VTK_POLY_LINE through ``points`` (m) per list of point indices in ``lines``."""
    offsets = np.cumsum([0] + [len(line) for line in lines])
    return vtk_grid.grid(points, POLY_LINE, offsets, np.concatenate(lines))


def _lift(points: FloatArray) -> FloatArray:
    """(n, 2) -> (n, 3) with z = 0."""
    out = np.zeros((len(points), 3))
    out[:, :2] = points
    return out


def _stream(streams: dict[str, ArrayStream], rows: FloatArray) -> None:
    """Rows (time, id, x, y, speed) on into the trajectories' ``streams``."""
    streams["points"].add(_lift(rows[:, 2:4]))
    streams["time"].add(rows[:, 0])
    streams["speed"].add(rows[:, 4])


class VtkRecorder:
    """Writes the files listed in the module doc into ``directory / "vtk"`` for the system
    ``spec``: ``record(frame, events)`` a frame (``events``: everything so far), ``close()``
    the trajectories and impacts (idempotent)."""

    def __init__(self, directory: Path, spec: System) -> None:
        self.directory = directory / "vtk"
        self.directory.mkdir(parents=True, exist_ok=True)
        self.spec = spec
        self.granules = PvdSeries(self.directory, "granules")
        self.hammers = PvdSeries(self.directory, "hammers")
        self.rotor = PvdSeries(self.directory, "rotor")
        self.hammers3d: PvdSeries | None = None
        self.rotor3d: PvdSeries | None = None
        self._hammers3d: vtk3d.Machine3D | None = None
        self._rotor3d: vtk3d.Machine3D | None = None
        self.frames = 0
        self.scratch = self.directory / ".trajectories.f8"
        self._scratch: BinaryIO | None = None
        self._streams: dict[str, ArrayStream] | None = None
        """The trajectories' points, times and speeds so far (None: to be rebuilt)."""
        self._impacts: list[Impact] = []
        self._impact_count = np.zeros(len(spec.granules), dtype=np.int64)  # by id, grows
        self._held = spec.has_bonds
        self._damage = spec.process.damage is not None
        self._hammer_outlines = [np.array(h.outline, dtype=float) for h in spec.hammers]
        self._disc = outline_or_circle(spec.rotor.outline, spec.rotor.radius, ROTOR_SIDES)
        self._closed = False
        self._started = False
        self._speed_max = 0.0

    def __getstate__(self) -> dict[str, object]:
        """The recorder as it stands (a checkpoint), with the trajectory scratch file's length
        in place of the open file and without the streams (rebuilt from the file)."""
        state = {k: v for k, v in self.__dict__.items() if k not in ("_scratch", "_streams")}
        state["_scratch_size"] = None if self._scratch is None else self._scratch.tell()
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        """Go on from a checkpoint: the scratch file cut back to its length then; the streams
        rebuilt from it at the next frame or at ``close``."""
        size = state.pop("_scratch_size")
        self.__dict__.update(state)
        self._scratch, self._streams = None, None
        if isinstance(size, int):
            self._scratch = os.fdopen(reopen_at(self.scratch, size), "wb")

    def _trajectory_streams(self) -> dict[str, ArrayStream]:
        """The trajectories' streams, rebuilt from the scratch file's rows if need be."""
        if self._streams is None:
            assert self._scratch is not None
            self._streams = {
                name: ArrayStream(self.directory / f".trajectories-{name}.z", np.float64, k)
                for name, k in (("points", 3), ("time", 1), ("speed", 1))
            }
            rows = self._scratch.tell() // (8 * SCRATCH_COLUMNS)
            if rows:
                shape = (rows, SCRATCH_COLUMNS)
                scratch = np.memmap(self.scratch, dtype=np.float64, mode="r", shape=shape)
                block = max(1, TRAJECTORY_BLOCK // SCRATCH_COLUMNS)
                for a in range(0, rows, block):
                    _stream(self._streams, np.asarray(scratch[a : a + block]))
                del scratch
        return self._streams

    def _start(self, frame: Frame) -> None:
        """Material names, the chamber and the ParaView state, at the first frame."""
        spec = self.spec
        self._scratch = open(self.scratch, "wb")  # noqa: SIM115 (closed by close())
        self.granules.comment = "material: " + ", ".join(
            f"{k} = {name}" for k, name in enumerate(frame.granules.material_names)
        )
        if spec.chamber is not None:
            c = spec.chamber
            wall = outline_or_circle(c.outline, c.radius, CHAMBER_SEGMENTS)
            ring = np.append(np.arange(len(wall)), 0)
            vtk_grid.save(_polylines([ring], wall), self.directory / "chamber.vtu")
        if spec.drawing is not None:
            self._start_3d()
        self._started = True

    def _start_3d(self) -> None:
        """The extruded parts, the ``hammers3d`` and ``rotor3d`` series and ``chamber3d.vtu``."""
        spec = self.spec
        drawing = spec.drawing
        assert drawing is not None
        self._hammers3d = vtk3d.Machine3D(self._hammer_outlines, drawing.hammer_thickness)
        self._rotor3d = vtk3d.Machine3D([self._disc], [drawing.rotor_thickness])
        self.hammers3d = PvdSeries(self.directory, "hammers3d")
        self.rotor3d = PvdSeries(self.directory, "rotor3d")
        if spec.chamber is not None:
            c = spec.chamber
            inner = outline_or_circle(c.outline, c.radius, CHAMBER_SEGMENTS)
            part = vtk3d.wall(inner, c.wall_thickness, drawing.chamber_height)
            vtk_grid.save(vtk3d.part_grid(part), self.directory / "chamber3d.vtu")

    def record(self, frame: Frame, events: Events) -> None:
        """Write the granule, hammer and rotor frames of ``frame`` and update the ``.pvd``."""
        if not self._started:
            self._start(frame)
        g, t = frame.granules, frame.time
        p, v, w = g.positions, g.velocities, g.angular_velocities
        speed = np.hypot(v[:, 0], v[:, 1])
        self._speed_max = max(self._speed_max, float(speed.max(initial=0.0)))
        new = events.impacts[len(self._impacts) :]
        self._impacts += new
        self._count([i.granule for i in new], int(g.ids.max(initial=-1)) + 1)

        data: dict[str, NDArray] = {
            "radius": g.radii,
            "velocity": _lift(v),
            "speed": speed,
            "angular_velocity": w,
            "kinetic_energy": 0.5 * g.masses * speed**2 + 0.5 * g.inertia * w**2,
            "id": g.ids,
            "material": g.materials,
            "impacts": self._impact_count[g.ids],
        }
        if self._held:
            data["held"] = g.held.astype(np.uint8)
        if self._damage:
            data["survival"], data["broken"] = g.survival, g.broken.astype(np.uint8)
        if g.contacts is not None and g.overlap_max is not None:
            data["contacts"], data["overlap_max"] = g.contacts, g.overlap_max
        drawing = self.spec.drawing
        if drawing is not None:
            data["thickness"] = np.full(len(p), drawing.granule_thickness)
        mesh = vtk_grid.vertices(p, data)
        self.granules.add(t, mesh)
        m = frame.machine
        hammers, rotor = hammer_cell_data(self.spec, m), rotor_cell_data(m)
        at_axis, rotor_angle = np.zeros((1, 2)), np.array([m.rotor_angle])
        self.hammers.add(t, machine_mesh(self._hammer_outlines, m.hinges, m.axis_angles, hammers))
        self.rotor.add(t, machine_mesh([self._disc], at_axis, rotor_angle, rotor))
        if self._hammers3d is not None and self._rotor3d is not None:
            assert self.hammers3d is not None and self.rotor3d is not None
            self.hammers3d.add(t, self._hammers3d.mesh(m.hinges, m.axis_angles, hammers))
            self.rotor3d.add(t, self._rotor3d.mesh(at_axis, rotor_angle, rotor))
        rows = np.column_stack((np.full(len(p), t), g.ids, p, speed))
        assert self._scratch is not None
        _stream(self._trajectory_streams(), rows)
        self._scratch.write(rows.tobytes())
        self._scratch.flush()
        if self.frames == 0:
            self._write_state()
        self.frames += 1

    def _write_state(self) -> None:
        """``paraview_state.py`` for the frames so far."""
        paraview_state.write(self.directory, self._speed_max, self.spec.chamber is not None)

    def _count(self, granules: list[int], ids: int) -> None:
        """Add impacts of ``granules`` (ids) to the counts, which cover ids below ``ids``."""
        size = max(ids, max(granules, default=-1) + 1, len(self._impact_count))
        if size > len(self._impact_count):
            self._impact_count = np.pad(self._impact_count, (0, size - len(self._impact_count)))
        np.add.at(self._impact_count, np.asarray(granules, dtype=np.int64), 1)

    def close(self, complete: bool = True) -> None:
        """Write ``trajectories.vtu`` and ``impacts.vtu`` (nothing if no frame was recorded);
        the trajectory scratch file is removed unless the run is not ``complete`` (it may be
        resumed from a checkpoint, which goes on with the file). Idempotent."""
        if self._closed or not self._started:
            return
        self._closed = True
        for series in (self.granules, self.hammers, self.rotor, self.hammers3d, self.rotor3d):
            if series is not None:
                series.close()
        self._write_state()
        try:
            self._write_trajectories()
        finally:
            if complete:
                self.scratch.unlink(missing_ok=True)
        self._write_impacts()

    def _write_trajectories(self) -> None:
        """``trajectories.vtu`` from the streams, its lines ordered by the scratch file's ids."""
        assert self._scratch is not None
        arrays = {name: stream.finish() for name, stream in self._trajectory_streams().items()}
        self._scratch.close()
        size = arrays["time"].rows
        if size == 0:  # no granule in any frame: an empty file
            vtk_grid.save(vtk_grid.vertices(np.zeros((0, 2))), self.directory / "trajectories.vtu")
            return
        shape = (size, SCRATCH_COLUMNS)
        scratch = np.memmap(self.scratch, dtype=np.float64, mode="r", shape=shape)
        ids = np.asarray(scratch[:, 1]).astype(np.int64)
        del scratch
        granules, counts = np.unique(ids, return_counts=True)
        trajectories = Grid(
            arrays["points"],
            POLY_LINE,
            np.concatenate(([0], np.cumsum(counts))),
            np.argsort(ids, kind="stable"),  # each granule's points in time order
            point_data={"time": arrays["time"], "speed": arrays["speed"]},
            cell_data={"id": granules},
        )
        vtk_grid.save(trajectories, self.directory / "trajectories.vtu")

    def _write_impacts(self) -> None:
        """``impacts.vtu``: every granule-hammer impact of the run."""
        impacts = self._impacts
        points = np.array([i.point for i in impacts], dtype=float).reshape(-1, 2)
        columns: dict[str, np.ndarray] = {
            name: np.array([getattr(i, name) for i in impacts], dtype=float)
            for name in ("time", "normal_impulse", "granule_energy_gain", "dissipated")
            + ("specific_energy",)
            + ("breakage_probability", "survival") * self._damage
        }
        for name in ("granule", "hammer"):
            columns[name] = np.array([getattr(i, name) for i in impacts], dtype=np.int64)
        columns["normal"] = _lift(np.array([i.normal for i in impacts], dtype=float).reshape(-1, 2))
        vtk_grid.save(vtk_grid.vertices(points, columns), self.directory / "impacts.vtu")


def hammer_cell_data(spec: System, machine: MachineFrame) -> dict[str, NDArray]:
    """Per hammer, the cell data of ``hammers.pvd`` (module doc)."""
    alpha = np.asarray(machine.swing_angles)
    mounts = np.array([h.angle_on_rotor for h in spec.hammers], dtype=float)
    return {
        "id": np.arange(len(alpha), dtype=np.int64),
        "swing_angle": alpha,
        "angle": machine.rotor_angle + mounts + alpha,
        "angular_velocity": np.asarray(machine.angular_velocities, dtype=float),
        "hinge_force": np.asarray(machine.hinge_forces, dtype=float),
    }


def rotor_cell_data(machine: MachineFrame) -> dict[str, NDArray]:
    """The cell data of ``rotor.pvd`` (module doc)."""
    return {
        "angle": np.array([machine.rotor_angle]),
        "angular_velocity": np.array([machine.rotor_angular_velocity]),
    }


def machine_mesh(
    outlines: Sequence[FloatArray],
    origins: FloatArray,
    angles: FloatArray,
    cell_data: dict[str, NDArray],
) -> Grid:
    """The parts (``outlines`` in their own frames, m) posed at ``origins`` (m) and ``angles``
    (rad), as polygons with ``cell_data``."""
    posed = []
    for outline, origin, angle in zip(outlines, origins, angles, strict=True):
        c, s = np.cos(angle), np.sin(angle)
        x, y = outline[:, 0], outline[:, 1]
        posed.append(np.column_stack((origin[0] + c * x - s * y, origin[1] + s * x + c * y)))
    offsets = np.cumsum([0] + [len(o) for o in posed])
    points = np.concatenate(posed)
    return vtk_grid.grid(
        points, POLYGON, offsets, np.arange(len(points), dtype=np.int64), cell_data=cell_data
    )
