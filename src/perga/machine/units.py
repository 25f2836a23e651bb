"""Scale factors between SI (the engine's interface) and the units Chipmunk works in.

Chipmunk's defaults assume game units (docs/pymunk.md): the bounding-box tree inflates each box by
0.1 × velocity × (1 time unit), ``collision_slop`` is a length and ``collision_bias`` and
``PivotJoint.error_bias`` are fractions of error left after one time unit. In SI a 20 m/s
granule would get a 2 m box and a 30 % overlap would still be there after 0.1 s. Inside Pymunk
perga therefore works in

    length 1 mm (1e-3 m), time 1 ms (1e-3 s), mass 1 g (1e-3 kg)

so that granule radii (~1 mm), speeds (1-50 m/s = 1-50 mm/ms), granule and hammer masses
(0.01-200 g) and time steps (1e-3 to 1e-1 ms) are all near 1. Derived units: velocity
1 m/s (unchanged), acceleration 1e3 m/s², force 1 N, impulse 1e-3 N·s, moment of inertia
1e-9 kg·m², energy 1e-3 J, angular velocity 1e3 rad/s. The box inflation is then
0.1 × v × 1 ms = 0.1 mm per m/s, about one granule radius at 10 m/s.

``COLLISION_SLOP`` (allowed overlap before position correction pushes back) is 1e-5 m: two
orders of magnitude below a granule radius, so it does not shift the geometry measurably, and
large enough that contacts resting on a face keep existing between steps.

Every conversion is a multiplication by a power of ten applied at the interface
(:mod:`perga.machine.machine` on the way in, :mod:`perga.engine.simulation` on the way out).
"""

from __future__ import annotations

LENGTH = 1e-3
"""m per internal length unit (1 mm)."""
TIME = 1e-3
"""s per internal time unit (1 ms)."""
MASS = 1e-3
"""kg per internal mass unit (1 g)."""

VELOCITY = LENGTH / TIME
"""m/s per internal velocity unit (= 1)."""
ACCELERATION = LENGTH / TIME**2
"""m/s² per internal acceleration unit (1e3)."""
ANGULAR_VELOCITY = 1.0 / TIME
"""rad/s per internal angular velocity unit (1e3)."""
MOMENT = MASS * LENGTH**2
"""kg·m² per internal moment-of-inertia unit (1e-9)."""
IMPULSE = MASS * VELOCITY
"""N·s per internal impulse unit (1e-3)."""
FORCE = MASS * ACCELERATION
"""N per internal force unit (1)."""
ENERGY = MASS * VELOCITY**2
"""J per internal energy unit (1e-3)."""

COLLISION_SLOP = 1e-5
"""Allowed contact overlap, m (set on the space in internal units: 0.01 mm)."""


def to_internal(value: float, unit: float) -> float:
    """SI value -> internal units, e.g. ``to_internal(0.002, LENGTH) == 2.0`` (mm)."""
    return value / unit


def to_si(value: float, unit: float) -> float:
    """Internal value -> SI, e.g. ``to_si(2.0, LENGTH) == 0.002`` (m)."""
    return value * unit


def vec_to_internal(value: tuple[float, float], unit: float) -> tuple[float, float]:
    """An SI 2-vector in internal units."""
    return (value[0] / unit, value[1] / unit)


def vec_to_si(value: tuple[float, float], unit: float) -> tuple[float, float]:
    """An internal 2-vector in SI."""
    return (value[0] * unit, value[1] * unit)
