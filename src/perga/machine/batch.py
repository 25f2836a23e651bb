"""Bulk, checked reads of chosen bodies' state (the rigid granules) and of every body of a space
(the rigid dissipation), and the one bulk write of their velocities, through ``pymunk.batch``
(with the arbiter meter, :mod:`perga.contact.rigid.dissipation`, the places it is used). The
machine's few bodies are read raw instead (:class:`~perga.machine.chipmunk_state.BodyViews`).

Reading ``body.position`` for every body in a Python loop costs an attribute access per
body; ``pymunk.batch.get_space_bodies`` copies the same numbers out of Chipmunk in one C pass
(docs/dev/performance.md has the gain). The batch API is experimental, so it is wrapped here and
nowhere else, with these properties:

* **It cannot select bodies.** ``get_space_bodies`` walks Chipmunk's body arrays: every
  dynamic *and kinematic* body (the rotor and hinged hammers as well as the granules; Chipmunk
  keeps kinematic bodies in its "dynamic" array), then the static ones (including
  ``space.static_body`` once Pymunk has created it), then sleeping bodies. There is no filter
  argument, so :class:`BodyReader` reads every body together with its ``BODY_ID`` and picks
  the chosen bodies' rows with an index array computed once from their ids.
* **The row order is not fixed.** Chipmunk removes a body by moving the last body of the array
  into its slot, and Pymunk adds ``space.static_body`` on first access. The reader therefore
  checks on every read, vectorised, that the ids at the cached rows are the chosen bodies' ids,
  and recomputes the rows (a sort and a binary search, no Python loop) when they are not. A
  chosen body that is no longer in the space raises :class:`LookupError`. There is no slow fallback:
  the only path is batch + index.
* **Buffers are checked.** The id buffer must hold one entry per body and the float buffer
  exactly ``len(fields)`` numbers per body, in the field order of the flags' bit values
  (position, angle, velocity, angular velocity); otherwise :class:`RuntimeError`. Building a
  reader also compares one read against the bodies' own properties, so a change of the
  experimental layout in a future Pymunk fails loudly instead of returning shifted numbers.
* **Writing is velocities only, through** :class:`BodyWriter`. ``pymunk.batch.
  set_space_bodies`` writes to *every* body (kinematic rotor, hammers, static bodies included),
  in the order of the body walk, and does not check the buffer length (a short buffer wrote
  NaN). The writer therefore never writes from a buffer of its own making: immediately before
  each write it reads every body's velocity and id into the batch buffer (one C pass), checks
  the ids and the buffer size as for a read, replaces only the chosen bodies' rows and writes that
  same buffer back, so every other body gets back the bits it holds. Only ``VELOCITY`` is
  written (positions are not: Chipmunk returns a position through the body's transform, which
  is not guaranteed to reproduce the stored bits for a body with an offset centre of gravity).
  Building a writer checks, once, that a write lands in the rows the reader found and
  nowhere else (a marked write, read back per body, then undone).

Values are copies (the batch buffer is reused), converted to SI by one multiplication by the
unit of :mod:`perga.machine.units`, i.e. bit-for-bit what ``np.array(body.position) * LENGTH``
gives. Rows are in the order of the bodies given. :class:`BodyWriter` works in Chipmunk's
internal units on both sides (its client, the effects' kicks, computes in them).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numba
import numpy as np
import pymunk
import pymunk.batch as pb
from numpy.typing import NDArray
from pymunk._chipmunk import ffi, lib

from perga.machine import units as u

FloatArray = NDArray[np.float64]
_F = pb.BodyFields

# floats per body of each readable field, in the order the batch iterator writes them
# (ascending flag value)
_WIDTH: dict[pb.BodyFields, int] = {
    _F.POSITION: 2,
    _F.ANGLE: 1,
    _F.VELOCITY: 2,
    _F.ANGULAR_VELOCITY: 1,
}
# field sets built once (enum arithmetic costs about a microsecond each time)
_ALL = _F.POSITION | _F.ANGLE | _F.VELOCITY | _F.ANGULAR_VELOCITY
_MOTION = _F.POSITION | _F.VELOCITY | _F.ANGULAR_VELOCITY
_PV = _F.POSITION | _F.VELOCITY
_V_ID = _F.VELOCITY | _F.BODY_ID
_ALL_ID = _ALL | _F.BODY_ID
_ALL_WIDTH = 6


class _BatchBuffer:
    """A ``pymunk.batch.Buffer`` filled and written back by the C iterators of
    ``pymunk.batch.get_space_bodies`` and ``set_space_bodies``, called directly with a C argument
    kept per field set (the wrappers allocate it and look the iterator up on every call), and
    read through numpy views of its C arrays, made again only when a fetch has
    reallocated them (instead of two buffer objects and two ``frombuffer`` calls a fetch)."""

    def __init__(self) -> None:
        self.buffer = pb.Buffer()
        self._arguments: dict[int, object] = {}
        self._pointers: tuple[object, object, int, int] | None = None
        self._ids = np.zeros(0, dtype=np.uintp)
        self._floats = np.zeros(0)

    def _argument(self, fields: pb.BodyFields) -> object:
        key = fields.value
        argument = self._arguments.get(key)
        if argument is None:
            argument = ffi.new("pmBatchedData *")
            argument.fields = key
            argument.floatArray = self.buffer._float_arr
            argument.intArray = self.buffer._int_arr
            self._arguments[key] = argument
        return argument

    def get(
        self, space: pymunk.Space, fields: pb.BodyFields
    ) -> tuple[NDArray[np.uintp], FloatArray]:
        """Fill the buffer with ``fields`` of every body (``get_space_bodies``); its id and float
        arrays, views valid until the next fetch."""
        ints, floats = self.buffer._int_arr, self.buffer._float_arr
        ints.num = 0
        floats.num = 0
        lib.cpSpaceEachBody(space._space, _GET_BODIES, self._argument(fields))
        pointers = (ints.arr, floats.arr, ints.max, floats.max)
        if pointers != self._pointers and ints.num:
            self._ids = np.frombuffer(ffi.buffer(ints.arr, ints.max * _ID_BYTES), dtype=np.uintp)
            self._floats = np.frombuffer(ffi.buffer(floats.arr, floats.max * 8), dtype=np.float64)
            self._pointers = pointers
        return self._ids[: ints.num], self._floats[: floats.num]

    def set(self, space: pymunk.Space, fields: pb.BodyFields) -> None:
        """Write ``fields`` of every body from the buffer (``set_space_bodies``)."""
        floats = self.buffer._float_arr
        count = floats.num
        floats.num = 0  # the iterator reads from the start, counting up
        lib.cpSpaceEachBody(space._space, _SET_BODIES, self._argument(fields))
        floats.num = count


_GET_BODIES = ffi.addressof(lib, "pmSpaceBodyGetIteratorFuncBatched")
_SET_BODIES = ffi.addressof(lib, "pmSpaceBodySetIteratorFuncBatched")
_ID_BYTES = ffi.sizeof("uintptr_t")


@functools.cache
def _layout(fields: pb.BodyFields) -> tuple[pb.BodyFields, int, tuple[slice, ...]]:
    """The fields to fetch (``fields`` and BODY_ID), the floats per body and the column slice of
    each requested field in a row of the float buffer (cached: enum arithmetic is slow)."""
    columns = []
    start = 0
    for flag in sorted(_WIDTH, key=lambda f: f.value):
        if flag in fields:
            columns.append(slice(start, start + _WIDTH[flag]))
            start += _WIDTH[flag]
    return fields | _F.BODY_ID, start, tuple(columns)


class BodyReader:
    """Reads the bodies ``bodies`` of ``space`` through ``pymunk.batch``, rows in their order.

    Build it once per space (it records the bodies' ids and verifies the batch layout
    once) and call it as often as needed; each call is one C pass over the space's bodies plus
    a few numpy operations.
    """

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body]) -> None:
        self._space = space
        self._bodies = list(bodies)
        self._ids = np.array([b.id for b in self._bodies], dtype=np.uintp)
        if np.unique(self._ids).size != self._ids.size:
            raise ValueError("bodies are not distinct")
        self._buffer = _BatchBuffer()
        self._rows = np.zeros(0, dtype=np.intp)
        if self._bodies:
            self._verify_layout()

    def __getstate__(self) -> dict[str, object]:
        """The space and the bodies (a checkpoint): the buffers are C memory, and a pickled
        body gets a new id, so both are made anew on unpickling."""
        return {"_space": self._space, "_bodies": self._bodies}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._buffer, self._write_buffer = _BatchBuffer(), _BatchBuffer()
        self._rows = np.zeros(0, dtype=np.intp)
        self._ids = np.zeros(0, dtype=np.uintp)  # the bodies may not be rebuilt yet: see _chosen

    def _chosen(self) -> NDArray[np.uintp]:
        """The chosen bodies' ids (taken again after unpickling, at the first read)."""
        if self._ids.size != len(self._bodies):
            self._ids = np.array([b.id for b in self._bodies], dtype=np.uintp)
        return self._ids

    @property
    def count(self) -> int:
        """Number of bodies read."""
        return len(self._bodies)

    def positions(self) -> FloatArray:
        """Positions of the bodies' local origins (a granule's centre), (n, 2), m."""
        (p,) = self._read(_F.POSITION)
        return p * u.LENGTH

    def velocities(self) -> FloatArray:
        """Velocities of the centres of gravity, (n, 2), m/s."""
        (v,) = self._read(_F.VELOCITY)
        return v * u.VELOCITY

    def angular_velocities(self) -> FloatArray:
        """Angular velocities, (n,), rad/s."""
        (w,) = self._read(_F.ANGULAR_VELOCITY)
        return w[:, 0] * u.ANGULAR_VELOCITY

    def read(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions (n, 2), m, velocities (n, 2), m/s, and angular velocities (n,), rad/s,
        from a single pass."""
        p, v, w = self._read(_MOTION)
        return p * u.LENGTH, v * u.VELOCITY, w[:, 0] * u.ANGULAR_VELOCITY

    def read_internal_space(self) -> tuple[NDArray[np.uintp], FloatArray]:
        """Every body of the space, internal units, from a single pass: their ids (in the batch
        walk's order) and rows (n_all, 6), each x, y (position), angle, vx, vy (velocity), ω
        (angular velocity); fresh arrays."""
        ids, floats = self._fetch(_ALL_ID, _ALL_WIDTH)
        return ids.copy(), floats.reshape(ids.size, _ALL_WIDTH).copy()

    # --- internals ---------------------------------------------------------------------------

    def _read(self, fields: pb.BodyFields) -> list[FloatArray]:
        """The chosen bodies' rows of each requested field (internal units, ascending flag order),
        each a fresh (n, width) array."""
        fetch, width, columns = _layout(fields)
        if not self._bodies:
            return [np.zeros((0, c.stop - c.start)) for c in columns]
        ids, floats = self._fetch(fetch, width)
        table = floats.reshape(ids.size, width)[self._rows_of(ids)]  # fancy indexing: a copy
        return [table[:, c] for c in columns]

    def _take(self, ids: NDArray[np.uintp], floats: FloatArray, out: FloatArray) -> None:
        """Copy the chosen bodies' rows of a fetch into ``out`` (one compiled call when the
        cached rows hold, the usual case)."""
        if not _take_rows(floats, ids, self._rows, self._chosen(), out):
            self._rows = self._locate(ids)
            _take_rows(floats, ids, self._rows, self._ids, out)

    def _rows_of(self, ids: NDArray[np.uintp]) -> NDArray[np.intp]:
        """The chosen bodies' rows in a batch read whose id column is ``ids`` (cached, checked)."""
        if not _rows_hold(ids, self._rows, self._chosen()):
            self._rows = self._locate(ids)
        return self._rows

    def _fetch(
        self, fields: pb.BodyFields, width: int, buffer: _BatchBuffer | None = None
    ) -> tuple[NDArray[np.uintp], FloatArray]:
        """One batch read of ``fields`` (must include BODY_ID) into ``buffer`` (default: the
        reader's) with its buffer sizes checked. The returned arrays are views of the reused
        buffer, valid until its next fetch; the float view is writable."""
        ids, floats = (self._buffer if buffer is None else buffer).get(self._space, fields)
        if floats.size != ids.size * width:
            raise RuntimeError(
                f"pymunk.batch returned {floats.size} floats for {ids.size} bodies, expected "
                f"{width} per body ({fields!r}): the experimental batch layout has changed"
            )
        return ids, floats

    def _locate(self, ids: NDArray[np.uintp]) -> NDArray[np.intp]:
        """Row of each chosen body in a batch read whose id column is ``ids``."""
        chosen = self._chosen()
        if ids.size == 0:
            missing = np.arange(chosen.size)
        else:
            order = np.argsort(ids, kind="stable")
            where = np.searchsorted(ids[order], chosen)
            where[where >= ids.size] = 0
            rows = order[where]
            missing = np.flatnonzero(ids[rows] != chosen)
        if missing.size:
            raise LookupError(
                f"bodies {missing[:10].tolist()} (indices in the reader's list) are not in "
                "the space"
            )
        return rows.astype(np.intp)

    def _verify_layout(self) -> None:
        """Compare one full read against the first and last body's own properties."""
        p, a, v, w = self._read(_ALL)
        for i in {0, len(self._bodies) - 1}:
            b = self._bodies[i]
            expected = [*b.position, b.angle, *b.velocity, b.angular_velocity]
            got = [*p[i], *a[i], *v[i], *w[i]]
            if not np.array_equal(got, expected, equal_nan=True):
                raise RuntimeError(
                    f"pymunk.batch layout check failed for body {i}: read {got}, the body "
                    f"holds {expected} (position, angle, velocity, angular velocity)"
                )


class BodyWriter(BodyReader):
    """A :class:`BodyReader` that can also set all its bodies' velocities in one batch write.

    Both :meth:`read_internal` and :meth:`write_internal_velocities` work in Chipmunk's internal
    units (mm/ms, mm). A write reads every body's velocity first and writes those bits back to
    every other body (module docstring), so it is safe at any time between steps;
    it is not meant for use inside ``space.step`` callbacks.
    """

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body]) -> None:
        super().__init__(space, bodies)
        self._write_buffer = _BatchBuffer()  # only ever filled by a fetch
        if self._bodies:
            self._verify_write()

    def read_internal(self, *, positions: bool) -> tuple[FloatArray, FloatArray | None]:
        """Granule velocities (n, 2), internal units, and their positions (n, 2) if asked for
        (else None), from one batch pass. Fresh arrays."""
        fetch, width, _ = _layout(_PV if positions else _F.VELOCITY)
        ids, floats = self._fetch(fetch, width)
        out = np.empty((len(self._bodies), width))
        self._take(ids, floats, out)
        return (out[:, 2:4], out[:, 0:2]) if positions else (out, None)

    def write_internal_velocities(self, velocities: FloatArray) -> None:
        """Set every chosen body's velocity (rows in the reader's order, (n, 2), internal units,
        finite); every other body keeps its velocity bit for bit."""
        new = np.asarray(velocities, dtype=np.float64)
        if new.shape != (len(self._bodies), 2):
            raise ValueError(
                f"expected velocities of shape ({len(self._bodies)}, 2), got {new.shape}"
            )
        if not _finite(new):
            bad = np.flatnonzero(~np.isfinite(new).all(axis=1))
            raise ValueError(f"non-finite velocities for bodies {bad[:10].tolist()}")
        if not self._bodies:
            return
        buffer = self._write_buffer
        ids, floats = self._fetch(_V_ID, 2, buffer)
        _put_rows(floats, 2, self._rows_of(ids), new)
        # the buffer holds exactly 2 floats per body in the walk's order, read just now
        buffer.set(self._space, _F.VELOCITY)

    def _verify_write(self) -> None:
        """Write marked velocities to the first and last body, check that exactly those
        bodies changed (per-body getters for them, a batch read for all), then undo it."""
        buffer = self._write_buffer
        ids, floats = self._fetch(_V_ID, 2, buffer)
        before_ids, before = ids.copy(), floats.reshape(-1, 2).copy()
        (original,) = self._read(_F.VELOCITY)
        marked = original.copy()
        ends = sorted({0, len(self._bodies) - 1})
        for k, i in enumerate(ends):
            marked[i] = original[i] + (1.0 + k, -2.0 - k)
        try:
            self.write_internal_velocities(marked)
            ids, floats = self._fetch(_V_ID, 2, buffer)
            expected = before.copy()
            rows = self._rows_of(before_ids)
            expected[rows[ends]] = marked[ends]
            per_body = [tuple(self._bodies[i].velocity) for i in ends]
            if (
                not np.array_equal(ids, before_ids)
                or not np.array_equal(floats.reshape(-1, 2), expected)
                or per_body != [tuple(marked[i]) for i in ends]
            ):
                raise RuntimeError(
                    "pymunk.batch.set_space_bodies check failed: a marked write of bodies "
                    f"{ends} did not land in their rows only (the experimental batch layout "
                    "has changed)"
                )
        finally:
            self.write_internal_velocities(original)
        if [tuple(self._bodies[i].velocity) for i in ends] != [tuple(original[i]) for i in ends]:
            raise RuntimeError("pymunk.batch.set_space_bodies check failed: undo did not restore")


@numba.njit(cache=True)
def _rows_hold(ids: np.ndarray, rows: np.ndarray, expected: np.ndarray) -> bool:
    """Whether ``rows`` of a batch read whose id column is ``ids`` hold the ids ``expected``."""
    if rows.size != expected.size:
        return False
    for j in range(rows.size):  # noqa: SIM110 (numba: no generators in all())
        if rows[j] >= ids.size or ids[rows[j]] != expected[j]:
            return False
    return True


@numba.njit(cache=True)
def _finite(values: np.ndarray) -> bool:
    """Whether every entry of the 2-D array ``values`` is finite."""
    for j in range(values.shape[0]):
        for c in range(values.shape[1]):
            if not math.isfinite(values[j, c]):
                return False
    return True


@numba.njit(cache=True)
def _take_rows(
    floats: np.ndarray, ids: np.ndarray, rows: np.ndarray, expected: np.ndarray, out: np.ndarray
) -> bool:
    """If ``rows`` of a fetch (flat ``floats``, ``out.shape[1]`` per body; id column ``ids``)
    hold the ids ``expected``, copy body ``rows[j]`` into ``out[j]`` and return True (else
    False, nothing copied)."""
    if not _rows_hold(ids, rows, expected):
        return False
    width = out.shape[1]
    for j in range(rows.size):
        base = rows[j] * width
        for c in range(width):
            out[j, c] = floats[base + c]
    return True


@numba.njit(cache=True)
def _put_rows(floats: np.ndarray, width: int, rows: np.ndarray, values: np.ndarray) -> None:
    """Copy ``values[j]`` into body ``rows[j]`` of the flat float buffer (``width`` per body)."""
    for j in range(rows.size):
        base = rows[j] * width
        for c in range(width):
            floats[base + c] = values[j, c]
