"""Chipmunk's state that pymunk's pickling does not carry (perga.machine.chipmunk_state): a
hinged hammer whose centre of gravity is off its origin, pickled alone, comes back moved and
flies off its hinge; with the raw state restored it steps on bit for bit. The layout checks
refuse offsets that are wrong."""

from __future__ import annotations

import pickle

import numba
import numpy as np
import pymunk
import pytest

from perga.machine import chipmunk_state
from perga.machine.chipmunk_state import (
    BodyViews,
    ChipmunkState,
    LayoutError,
    capture,
    restore,
)


def hinged_hammer() -> pymunk.Space:
    """A kinematic rotor turning at 0.3 rad per time unit and a hammer on a pivot joint, its
    mass set explicitly with the centre of gravity 25 units from its origin (as perga's plate
    hammers are), a swing stop holding it 0.2-0.3 rad ahead of the rotor (engaged, so that its
    impulse is not zero) and a saturated friction motor: the three joint kinds perga uses."""
    space = pymunk.Space()
    rotor = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    rotor.angular_velocity = 0.3
    hammer = pymunk.Body(28.0, 9420.0)
    hammer.center_of_gravity = (25.0, 0.0)
    hammer.position = (100.0, 0.0)
    shape = pymunk.Poly(hammer, [(-5, -10), (55, -10), (55, 10), (-5, 10)])
    joints = [
        pymunk.PivotJoint(rotor, hammer, (100.0, 0.0), (0.0, 0.0)),
        pymunk.RotaryLimitJoint(rotor, hammer, 0.2, 0.3),
        pymunk.SimpleMotor(hammer, rotor, 0.0),
    ]
    joints[2].max_force = 50.0
    space.add(rotor, hammer, shape, *joints)
    for _ in range(20):
        space.step(0.05)
    return space


def hammer_of(space: pymunk.Space) -> pymunk.Body:
    return next(b for b in space.bodies if b.body_type == pymunk.Body.DYNAMIC)


def trajectory(space: pymunk.Space, steps: int = 100) -> np.ndarray:
    body, rows = hammer_of(space), []
    for _ in range(steps):
        space.step(0.05)
        rows.append([*body.position, body.angle, *body.velocity, body.angular_velocity])
    return np.array(rows)


def test_pickle_alone_moves_the_hammer_and_the_raw_state_puts_it_back():
    space = hinged_hammer()
    state = capture(space)
    alone = pickle.loads(pickle.dumps(space))
    restored = pickle.loads(pickle.dumps(space))
    restore(restored, state)
    reference = trajectory(space)
    # pymunk sets the position before the centre of gravity: the hammer comes back displaced
    # and its joint throws it (a difference of the order of the hammer itself, 25 units)
    assert np.abs(trajectory(alone) - reference).max() > 1.0
    assert np.array_equal(trajectory(restored), reference)


def test_the_joints_warm_start_is_carried():
    """Restoring the bodies but not the joints' accumulated impulses changes the motion (the
    solver starts cold); restoring both does not."""
    space = hinged_hammer()
    state = capture(space)
    assert np.any(state.joints != 0.0)
    cold = pickle.loads(pickle.dumps(space))
    restore(cold, ChipmunkState(state.bodies, np.zeros_like(state.joints)))
    reference = trajectory(space)
    assert not np.array_equal(trajectory(cold), reference)


@pytest.mark.parametrize(
    ("table", "key", "wrong"),
    [
        ("_JACC", pymunk.PivotJoint, (23, 2)),
        ("_JACC", pymunk.SimpleMotor, (14, 1)),
        ("_JACC", pymunk.RotaryLimitJoint, (16, 1)),
        ("_OWN", pymunk.PivotJoint, ("anchor_a", 15)),
    ],
)
def test_a_wrong_joint_offset_is_refused(monkeypatch, table, key, wrong):
    monkeypatch.setitem(getattr(chipmunk_state, table), key, wrong)
    with pytest.raises(LayoutError):
        capture(hinged_hammer())


@pytest.mark.parametrize("name", ["_M", "_I", "_V", "_COG", "_A", "_W", "_TX"])
def test_a_wrong_body_offset_is_refused(monkeypatch, name):
    monkeypatch.setattr(chipmunk_state, name, getattr(chipmunk_state, name) + 1)
    with pytest.raises(LayoutError):
        capture(hinged_hammer())


@pytest.mark.parametrize("name", ["VIEW_F", "VIEW_T"])
def test_a_wrong_force_offset_is_refused(monkeypatch, name):
    """The force and torque are written raw: an offset one double off is refused when the
    views are made (a marked force set through pymunk does not read back)."""
    monkeypatch.setattr(chipmunk_state, name, getattr(chipmunk_state, name) + 1)
    with pytest.raises(LayoutError):
        BodyViews([hammer_of(hinged_hammer())]).views()


def test_body_views_read_and_write_the_struct():
    """A view reads the body's angle and velocity as pymunk's getters do; a force and torque
    written into it are the body's; the marked check leaves them as they were."""
    body = hammer_of(hinged_hammer())
    body.force, body.torque = (0.5, 0.25), -0.125
    (view,) = BodyViews([body]).views()
    assert (*body.force, body.torque) == (0.5, 0.25, -0.125)
    assert view[chipmunk_state.VIEW_ANGLE] == body.angle
    assert tuple(view[chipmunk_state.VIEW_V : chipmunk_state.VIEW_V + 2]) == tuple(body.velocity)
    view[chipmunk_state.VIEW_F], view[chipmunk_state.VIEW_T] = 4.0, 5.0
    assert (body.force.x, body.torque) == (4.0, 5.0)


def test_views_are_refused_where_bodies_may_sleep():
    """Raw writes skip waking a body: a space that lets bodies sleep is refused, one that never
    does (pymunk's default, perga's) is not."""
    space = hinged_hammer()
    BodyViews([hammer_of(space)]).views()
    space.sleep_time_threshold = 1.0
    with pytest.raises(ValueError, match="sleep"):
        BodyViews([hammer_of(space)]).views()


def test_body_views_are_made_again_after_pickling():
    """Pickled as the bodies alone: the copy's views are those of the copy's bodies."""
    space = hinged_hammer()
    views = BodyViews([hammer_of(space)])
    views.views()
    copy = pickle.loads(pickle.dumps((space, views)))[1]
    (view,) = copy.views()
    (body,) = copy.bodies
    assert body is not hammer_of(space)
    view[chipmunk_state.VIEW_T] = 6.0
    assert body.torque == 6.0 and hammer_of(space).torque != 6.0


@numba.njit
def _write_torque(addresses, torque):
    """Compiled code writing body 0's torque through its address (as ``machine.write_loads``)."""
    raw = chipmunk_state.doubles_at(addresses[0], chipmunk_state.VIEW_WIDTH)
    old = raw[chipmunk_state.VIEW_T]
    raw[chipmunk_state.VIEW_T] = torque
    return old


PATHS = {"compiled": lambda f: f, "python": lambda f: f.py_func}
"""Compiled code, and the same function as plain Python (as with numba's JIT off: the mutation
runs), where ``doubles_at`` and ``space_step`` go through ctypes."""


@pytest.mark.parametrize("path", PATHS)
def test_addresses_reach_the_struct_and_are_taken_again_after_pickling(path):
    """Code reads and writes a body through its view's address; a pickled copy's addresses
    are those of the copy's bodies, not the original's."""
    write_torque = PATHS[path](_write_torque)
    space = hinged_hammer()
    body = hammer_of(space)
    body.torque = 1.5
    views = BodyViews([body])
    assert write_torque(views.addresses(), 2.5) == 1.5
    assert body.torque == 2.5
    copy_space, copy = pickle.loads(pickle.dumps((space, views)))
    assert write_torque(copy.addresses(), 7.0) == 2.5
    assert hammer_of(copy_space).torque == 7.0 and body.torque == 2.5


@numba.njit
def _steps(function: int, space: int, dt: float, n: int) -> None:
    for _ in range(n):
        chipmunk_state.space_step(function, space, dt)


@pytest.mark.parametrize("path", PATHS)
def test_the_space_stepped_through_its_address_steps_as_pymunk_does(path) -> None:
    """The hinged hammer stepped 200 times by ``cpSpaceStep`` through its address (from
    compiled code, or through ctypes) and by ``Space.step``: the same floats in every body and
    joint."""
    ours, theirs = hinged_hammer(), hinged_hammer()
    raw = chipmunk_state.raw_space_step(ours)
    assert raw is not None
    PATHS[path](_steps)(*raw, 0.01, 200)
    for _ in range(200):
        theirs.step(0.01)
    a, b = capture(ours), capture(theirs)
    np.testing.assert_array_equal(a.bodies, b.bodies)
    np.testing.assert_array_equal(a.joints, b.joints)


def test_a_space_whose_step_has_python_work_is_not_stepped_raw() -> None:
    """Bodies to check, objects waiting, a collision handler, a post-step callback: pymunk's
    ``Space.step`` has work besides ``cpSpaceStep``, so no raw step is offered; a space with
    none is."""
    space = hinged_hammer()
    assert chipmunk_state.raw_space_step(space) is not None
    space.add(pymunk.Body(1.0, 1.0))
    assert chipmunk_state.raw_space_step(space) is None  # a body added: checked at a step
    space.step(0.01)
    assert chipmunk_state.raw_space_step(space) is not None
    space.add_post_step_callback(lambda space, key: None, "key")
    assert chipmunk_state.raw_space_step(space) is None
    space.step(0.01)
    assert chipmunk_state.raw_space_step(space) is not None
    space.on_collision(1, 2, begin=lambda arbiter, space, data: None)
    assert chipmunk_state.raw_space_step(space) is None
