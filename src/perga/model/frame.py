"""A frame: an immutable snapshot of one instant of a simulation as plain arrays, SI units.

The simulation makes frames (:meth:`perga.engine.simulation.Simulation.frame`); recorders and
writers (tables, VTK, the summary) read nothing else of it. Arrays are read-only: a frame can be
kept, compared or sent to another process without copying and without aliasing the simulation.
Rows of the granule arrays are granules in the spec's order, rows of the machine arrays hammers
in the spec's order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perga.model.records import EnergyLedger

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def frozen(array: np.ndarray) -> np.ndarray:
    """``array`` marked read-only (the same object)."""
    array.flags.writeable = False
    return array


@dataclass(frozen=True)
class GranuleFrame:
    """The granules at one instant.

    ids (n,): index in the spec; radii (n,), m; masses (n,), kg; inertia (n,): moment about the
    centre, kg·m² (m r²/2; 0 for a sliding point, whose spin never changes); materials (n,):
    index into ``material_names`` (sorted); positions (n, 2), m; velocities (n, 2), m/s;
    angular_velocities (n,), rad/s; contacts (n,): contacts now and overlap_max (n,): the largest
    of their overlaps, m, where the contact model has overlaps (soft), else None.
    """

    ids: IntArray
    radii: FloatArray
    masses: FloatArray
    inertia: FloatArray
    materials: NDArray[np.int32]
    material_names: tuple[str, ...]
    positions: FloatArray
    velocities: FloatArray
    angular_velocities: FloatArray
    held: NDArray[np.bool_]
    survival: FloatArray
    broken: NDArray[np.bool_]
    damaging_impacts: NDArray[np.int64]
    contacts: NDArray[np.int32] | None = None
    overlap_max: FloatArray | None = None

    @property
    def speeds(self) -> FloatArray:
        """|v|, m/s."""
        return np.hypot(self.velocities[:, 0], self.velocities[:, 1])


@dataclass(frozen=True)
class MachineFrame:
    """Rotor and hammers at one instant.

    rotor_angle: rad; rotor_angular_velocity: rad/s; hinges (h, 2): where the origin of each
    hammer's frame (its hinge) is, m; axis_angles (h,): the direction of each hammer's axis (the
    +x of its frame), rad; swing_angles (h,): α, the axis against the radial line through the
    hinge, rad; angular_velocities (h,): absolute, rad/s; velocities (h, 2): of the centres of
    mass, m/s; hinge_forces (h,): magnitude of the hinge reaction over the last machine step, N
    (0 for welded and free hammers).
    """

    rotor_angle: float
    rotor_angular_velocity: float
    hinges: FloatArray
    axis_angles: FloatArray
    swing_angles: FloatArray
    angular_velocities: FloatArray
    velocities: FloatArray
    hinge_forces: FloatArray

    def posed(self, outlines: list[FloatArray]) -> list[FloatArray]:
        """Each hammer's outline (its frame: hinge at the origin, axis +x, m) in the world, m."""
        out = []
        for outline, hinge, angle in zip(outlines, self.hinges, self.axis_angles, strict=True):
            c, s = np.cos(angle), np.sin(angle)
            x, y = outline[:, 0], outline[:, 1]
            out.append(np.column_stack((hinge[0] + c * x - s * y, hinge[1] + s * x + c * y)))
        return out


@dataclass(frozen=True)
class Frame:
    """The simulation at time ``time`` (s) after ``step`` machine steps: its granules, its
    machine and, where the run measures it, the energy ledger since t = 0; the counts so far:
    granule-hammer impacts, granules fed in all (those at t = 0 included), gone through the
    outlet, drawn broken, removed broken, released from their cells."""

    time: float
    step: int
    granules: GranuleFrame
    machine: MachineFrame
    energy: EnergyLedger | None = None
    impacts: int = 0
    fed: int = 0
    departed: int = 0
    broken: int = 0
    removed_broken: int = 0
    released: int = 0
