"""Chipmunk state that pymunk's pickling does not carry exactly, read and written raw.

pymunk pickles a space with its bodies, shapes, joints and cached contacts, but two things come
back changed: a body's centre-of-gravity position ``p`` (pymunk sets ``position`` before
``center_of_gravity``, and Chipmunk derives ``p`` from the position with the centre of gravity
it holds at that moment, so a hammer whose centre of gravity is off its origin is moved by
R·cog), and every joint's accumulated impulse ``jAcc`` (the solver's warm start; not pickled).
Both are kept here as the doubles of Munk2D's structs (``chipmunk_structs.h``: ``cpBody``,
``cpPivotJoint``, ``cpSimpleMotor``, ``cpRotaryLimitJoint``), read and written through the
bodies' and joints' C pointers. The offsets are checked against pymunk's own getters (mass,
moment, centre of gravity, velocity, angle, position; each joint's impulse, |jAcc|) every time,
so a pymunk whose layout differs is refused, never read wrongly.
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
import pymunk
from llvmlite import ir
from numba import types
from numba.extending import intrinsic, overload
from numpy.typing import NDArray
from pymunk._chipmunk import ffi, lib

# cpBody as doubles (x86-64 and every LP64/LLP64 ABI: pointers and doubles are 8 bytes):
# 0 velocity_func, 1 position_func, 2 m, 3 m_inv, 4 i, 5 i_inv, 6-7 cog, 8-9 p, 10-11 v,
# 12-13 f, 14 a, 15 w, 16 t, 17-22 transform (a b c d tx ty)
_BODY = slice(2, 23)
_M, _I, _COG, _P, _V, _F, _A, _W, _T, _TX = 2, 4, 6, 8, 10, 12, 14, 15, 16, 21
# cpConstraint is 13 doubles (6 pointers, maxForce, errorBias, maxBias, cpBool padded, 3
# pointers); each joint's own fields follow it
_MAX_FORCE = 6
_JACC = {pymunk.PivotJoint: (25, 2), pymunk.SimpleMotor: (15, 1), pymunk.RotaryLimitJoint: (17, 1)}
"""Joint class: (index of jAcc in doubles, its length)."""
_OWN = {
    pymunk.PivotJoint: ("anchor_a", 13),
    pymunk.SimpleMotor: ("rate", 13),
    pymunk.RotaryLimitJoint: ("min", 13),
}
"""Joint class: (a property, the index of its first double), for the layout check."""


class LayoutError(RuntimeError):
    """This pymunk's C structs are not laid out as this module knows them."""


@dataclass(frozen=True)
class ChipmunkState:
    """The raw doubles of every body of a space (in ``space.bodies`` order; m to the
    transform) and every joint's jAcc (in ``space.constraints`` order)."""

    bodies: NDArray[np.float64]
    joints: NDArray[np.float64]


def _doubles(pointer: object) -> object:
    return ffi.cast("double *", pointer)


def _check_body(body: pymunk.Body, raw: NDArray[np.float64]) -> None:
    expected = {
        "mass": (raw[_M - 2], body.mass),
        "moment": (raw[_I - 2], body.moment),
        "centre of gravity": (tuple(raw[_COG - 2 : _COG]), tuple(body.center_of_gravity)),
        "velocity": (tuple(raw[_V - 2 : _V]), tuple(body.velocity)),
        "angle": (raw[_A - 2], body.angle),
        "angular velocity": (raw[_W - 2], body.angular_velocity),
        "position": (tuple(raw[_TX - 2 : _TX]), tuple(body.position)),
    }
    for name, (read, held) in expected.items():
        if read != held and not (read != read and held != held):  # NaN-safe equality
            raise LayoutError(
                f"pymunk's cpBody layout changed: the {name} read raw is {read}, pymunk's getter "
                f"gives {held} (perga knows pymunk {pymunk.version}'s Munk2D layout)"
            )


def _joint_layout(joint: pymunk.Constraint) -> tuple[int, int]:
    kind = type(joint)
    if kind not in _JACC:
        raise LayoutError(f"no known layout for the joint {kind.__name__}")
    raw = _doubles(joint._constraint)
    name, first = _OWN[kind]
    own = getattr(joint, name)
    own = tuple(own) if isinstance(own, tuple | pymunk.Vec2d) else (own,)
    read = tuple(raw[first + k] for k in range(len(own)))
    if read != own or raw[_MAX_FORCE] != joint.max_force:
        raise LayoutError(
            f"pymunk's {kind.__name__} layout changed: read {read} and max force "
            f"{raw[_MAX_FORCE]}, pymunk gives {own} and {joint.max_force}"
        )
    return _JACC[kind]


def capture(space: pymunk.Space) -> ChipmunkState:
    """The space's bodies and joints as raw doubles (checked against pymunk's getters)."""
    rows = []
    for body in space.bodies:
        raw = _doubles(body._body)
        row = np.array([raw[k] for k in range(_BODY.start, _BODY.stop)])
        _check_body(body, row)
        rows.append(row)
    joints = []
    for joint in space.constraints:
        first, length = _joint_layout(joint)
        raw = _doubles(joint._constraint)
        values = [raw[first + k] for k in range(length)]
        length_read = math.sqrt(sum(v * v for v in values))  # cpvlength, cpfabs
        if length_read != joint.impulse:
            raise LayoutError(
                f"pymunk's {type(joint).__name__} layout changed: |jAcc| read raw is "
                f"{length_read}, its impulse is {joint.impulse}"
            )
        joints.extend(values)
    width = _BODY.stop - _BODY.start
    return ChipmunkState(np.array(rows).reshape(-1, width), np.array(joints, dtype=float))


def restore(space: pymunk.Space, state: ChipmunkState) -> None:
    """Write ``state`` (from :func:`capture` of the space this one was unpickled from) into
    the space's bodies and joints, bit for bit."""
    bodies = list(space.bodies)
    if len(bodies) != state.bodies.shape[0]:
        raise ValueError(f"{len(bodies)} bodies, the state holds {state.bodies.shape[0]}")
    for body, row in zip(bodies, state.bodies, strict=True):
        raw = _doubles(body._body)
        for k, value in enumerate(row):
            raw[_BODY.start + k] = value
        _check_body(body, row)
    values = iter(state.joints)
    for joint in space.constraints:
        first, length = _joint_layout(joint)
        raw = _doubles(joint._constraint)
        for k in range(length):
            raw[first + k] = next(values)
    if next(values, None) is not None:
        raise ValueError("the state holds more joint impulses than the space has joints")


VIEW_P, VIEW_V, VIEW_F, VIEW_ANGLE, VIEW_W, VIEW_T = (
    k - _BODY.start for k in (_P, _V, _F, _A, _W, _T)
)
VIEW_TRANSFORM = _TX - 4 - _BODY.start
"""Index in a :class:`BodyViews` view of each field's first double: the centre of gravity's
position p (2), velocity (2), force (2), angle, angular velocity, torque, transform (6: a b c d
tx ty)."""


@intrinsic
def _double_pointer(typingctx, address):
    """The integer ``address`` as a pointer to doubles (compiled code only)."""
    if not isinstance(address, types.Integer):
        return None
    pointer = types.CPointer(types.float64)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], context.get_value_type(pointer))

    return pointer(address), codegen


def doubles_at(address: int, length: int) -> NDArray[np.float64]:
    """The ``length`` doubles at ``address`` (an entry of :meth:`_StructViews.addresses`) as a
    writable array: in compiled code a pointer (:func:`_doubles_at_compiled`), in Python (numba's
    JIT off: mutation tests, debugging) through ctypes."""
    return np.ctypeslib.as_array((ctypes.c_double * length).from_address(int(address)))


@overload(doubles_at, inline="always")
def _doubles_at_compiled(address, length):
    return lambda address, length: numba.carray(_double_pointer(address), (length,))


def raw_space_step(space: pymunk.Space) -> tuple[int, int] | None:
    """The addresses of Chipmunk's ``cpSpaceStep`` and of ``space``'s struct, for compiled code
    that steps the space itself (:func:`space_step`), or None while pymunk's ``Space.step``
    has work of its own besides that call: collision handlers (Python callbacks that may add or
    remove objects, deferred by the lock ``Space.step`` holds), objects waiting to be added or
    removed, post-step callbacks, bodies to check, or a threaded space."""
    if (
        space.threaded
        or space._handlers
        or space._add_later
        or space._remove_later
        or space._post_step_callbacks
        or space._bodies_to_check
    ):
        return None
    function = int(ffi.cast("uintptr_t", ffi.addressof(lib, "cpSpaceStep")))
    return function, int(ffi.cast("uintptr_t", space._space))


@intrinsic
def _call_space_step(typingctx, function, space, dt):
    """``cpSpaceStep(space, dt)`` through the integer addresses ``function`` and ``space``."""
    if not (
        isinstance(function, types.Integer)
        and isinstance(space, types.Integer)
        and dt == types.float64
    ):
        return None

    def codegen(context, builder, signature, args):
        address, struct, step = args
        pointer = ir.IntType(8).as_pointer()
        callee = ir.FunctionType(ir.VoidType(), [pointer, ir.DoubleType()]).as_pointer()
        builder.call(builder.inttoptr(address, callee), [builder.inttoptr(struct, pointer), step])
        return context.get_dummy_value()

    return types.none(function, space, dt), codegen


def space_step(function: int, space: int, dt: float) -> None:
    """Chipmunk's step of ``space`` by ``dt`` (internal time units) through the addresses of
    :func:`raw_space_step`; what pymunk's ``Space.step`` does while that gives addresses, with
    less overhead a call (docs/dev/performance.md). In Python (numba's JIT off) through ctypes."""
    ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_double)(int(function))(int(space), dt)


@overload(space_step, inline="always")
def _space_step_compiled(function, space, dt):
    return lambda function, space, dt: _call_space_step(function, space, dt)


VIEW_WIDTH = _BODY.stop - _BODY.start
"""Doubles in a :class:`BodyViews` view."""


class _StructViews:
    """Numpy views of the C structs of pymunk objects ``items``, one per object, made (and
    checked, :meth:`_view`) at the first :meth:`views`; they live as long as this object holds
    the objects. Pickled as the objects alone (the views are made again): take them from
    :meth:`views` at each use, as a view kept elsewhere comes back from a checkpoint as a copy
    that no longer follows the struct."""

    def __init__(self, items: list[Any]) -> None:
        self.items = items
        self._views: tuple[NDArray[np.float64], ...] | None = None
        self._addresses: NDArray[np.uint64] | None = None

    def __getstate__(self) -> dict[str, object]:
        return {"items": self.items}

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._views = None
        self._addresses = None

    def views(self) -> tuple[NDArray[np.float64], ...]:
        """One writable view per object, in their order."""
        if self._views is None:
            self._views = tuple(self._view(item) for item in self.items)
        return self._views

    def addresses(self) -> NDArray[np.uint64]:
        """The address of each view's first double, in their order, for compiled code to read
        and write through (:func:`doubles_at`): one array passes to a compiled function in a
        third of the time a tuple of views takes (docs/dev/performance.md)."""
        if self._addresses is None:
            self._addresses = np.array([v.ctypes.data for v in self.views()], dtype=np.uint64)
        return self._addresses

    def _view(self, item: Any) -> NDArray[np.float64]:
        """The checked view of ``item``'s struct."""
        raise NotImplementedError


class BodyViews(_StructViews):
    """A (21,) view of each of ``bodies``' C structs (cpBody's doubles m to the transform,
    indices ``VIEW_*``), so that compiled code reads a body's state and sets its force and
    torque without a call into Chipmunk; each checked against pymunk's getters (as
    :func:`capture`) and by a marked force and torque set through pymunk and read back raw.
    Writing ``f`` and ``t`` raw is pymunk's setter without ``cpBodyActivate``, which only wakes
    sleeping bodies: refused for a space that lets bodies sleep."""

    @property
    def bodies(self) -> list[pymunk.Body]:
        return self.items

    def _view(self, item: Any) -> NDArray[np.float64]:
        return _body_view(item)


def _body_view(body: pymunk.Body) -> NDArray[np.float64]:
    """The checked view of ``body``'s doubles m to the transform (:class:`BodyViews`)."""
    space = body.space
    if space is not None and space.sleep_time_threshold != math.inf:
        raise ValueError("raw force writes skip waking bodies: the space must not let them sleep")
    raw = _doubles(body._body)
    width = _BODY.stop - _BODY.start
    view = np.frombuffer(ffi.buffer(raw + _BODY.start, width * ffi.sizeof("double")))
    _check_body(body, view)
    force, torque = body.force, body.torque
    body.force, body.torque = (1.5, -2.5), 3.25
    marked = (view[VIEW_F], view[VIEW_F + 1], view[VIEW_T])
    body.force, body.torque = force, torque
    if marked != (1.5, -2.5, 3.25):
        raise LayoutError(
            f"pymunk's cpBody layout changed: a force (1.5, -2.5) and torque 3.25 set through "
            f"pymunk read raw as {marked} (perga knows pymunk {pymunk.version}'s Munk2D layout)"
        )
    return view


class JointImpulses(_StructViews):
    """The accumulated impulses of ``joints`` (jAcc: a PivotJoint's J, (x, y), applied +J to
    its body b and −J to a; a SimpleMotor's or RotaryLimitJoint's angular j, +j on b), read raw
    after every step: a view of each joint's jAcc in its struct (two doubles for a pivot, one
    otherwise, internal units), its layout checked when the view is made."""

    @property
    def joints(self) -> list[pymunk.Constraint]:
        return self.items

    def _view(self, item: Any) -> NDArray[np.float64]:
        return _joint_view(item, *_joint_layout(item))

    def read(self) -> NDArray[np.float64]:
        """Every joint's jAcc, one after the other, internal units (a fresh array)."""
        views = self.views()
        return np.concatenate(views) if views else np.zeros(0)


def _joint_view(joint: pymunk.Constraint, first: int, length: int) -> NDArray[np.float64]:
    """The doubles first:first + length of ``joint``'s C struct, a writable view."""
    raw = _doubles(joint._constraint)
    return np.frombuffer(ffi.buffer(raw + first, length * ffi.sizeof("double")), dtype=np.float64)
