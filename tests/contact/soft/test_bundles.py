"""The kernel's named bundles: ``PolygonSet.arrays()``/``loads()``, ``ContactTable.arrays()``
and the plain tuples ``SoftGranules`` passes ``kernel.advance`` hold the arrays their field
names say, and ``advance`` gives the same result whether it gets named or plain tuples."""

import math

import numpy as np

from perga.contact.soft import SoftGranules, chamber, contact_parameters, kernel, uniform_table
from perga.contact.soft.granules import opening_of
from perga.contact.soft.polygon_set import (
    FREE,
    HIST_NORMAL_IMPULSE,
    PINNED,
    PolygonArrays,
    PolygonLoads,
    TableArrays,
    contact_table,
    polygon_set,
)
from perga.machine.effects import FloorKick

from .test_polygons import _box, _hexagon

R = 2e-3  # m


def _scene() -> SoftGranules:
    """A few granules falling onto a hinged plate and a free hexagon in a round chamber."""
    plate = _box(0.03, 0.004, 0.0, -0.01)
    hexagon = _hexagon(0.006, (0.0, 0.012))
    polys = polygon_set(
        [plate, hexagon],
        np.array([[0.0, -0.01], [0.0, 0.012]]),
        kind=[PINNED, FREE],
        mass=[math.inf, 0.02],
        inertia=[1e-5, 4e-7],
        pivot=np.array([[-0.015, -0.01], [0.0, 0.0]]),
        velocity=np.array([[0.0, 0.0], [0.1, 0.0]]),
        omega=np.array([30.0, -5.0]),
    )
    x = np.array([[-0.01, -0.006], [0.0, -0.0059], [0.01, -0.004], [0.004, 0.02], [0.0, 0.03]])
    n = len(x)
    row = contact_parameters("linear", 0.7, k_n=1e5, friction=0.5, rolling=0.05)
    return SoftGranules(
        x, np.full(n, R), np.full(n, 1e-4), uniform_table(row), v=np.full((n, 2), -0.5),
        walls=[chamber(0.05)], gravity=(0.0, -9.81),
        polygons=polys, polygon_table=contact_table(1e5, 2e4, 0.6, 0.4),
    )  # fmt: skip


def _same(bundle, source) -> None:
    """Each field of ``bundle`` is the attribute of ``source`` of its name (the same object)."""
    for name in bundle._fields:
        assert getattr(bundle, name) is getattr(source, name), name


def test_polygon_and_table_bundles_hold_their_fields():
    g = _scene()
    _same(g.polygons.arrays(), g.polygons)
    _same(g.polygons.loads(), g.polygons)
    _same(g.polygon_table.arrays(), g.polygon_table)


def test_plain_tuples_for_advance_follow_the_field_order():
    """``SoftGranules._bundles`` builds plain tuples by position; named, each field is the
    array of its name."""
    g = _scene()
    polys, table = g.polygons, g.polygon_table
    settings, state, props, bonds, params, walls, polygons, nbrs, work = g._bundles(
        polys, table, 7, 0.5, 3.0, True
    )
    named = kernel.Settings(*settings)
    assert (named.n_steps, named.dt, named.skin, named.drag, named.v_cap, named.first_step) == (
        7,
        g.dt,
        g.skin,
        0.5,
        3.0,
        g.steps,
    )
    assert named.gravity is g.gravity and named.pairs is True and named.rebuild is True
    assert named.coast is True
    _same(kernel.Granules(*state), g)
    _same(kernel.GranuleProps(*props), g)
    _same(kernel.Bonds(*bonds), g)
    assert params is g.params
    named = kernel.Walls(*walls)
    assert named.rows is g.walls and named.hist is g.wall_hist
    named = kernel.Polygons(*polygons)
    _same(PolygonArrays(*named.arrays), polys)
    _same(TableArrays(*named.table), table)
    _same(PolygonLoads(*named.loads), polys)
    assert named.hist is g.polygon_hist
    assert all(a is b for a, b in zip(kernel.CandidateList(*named.listed), g._listed, strict=True))
    named = kernel.NeighbourList(*nbrs)
    assert named.start is g.start and named.nbr is g.nbr
    assert named.hist is g.hist and named.x_ref is g.x_ref
    named = kernel.Work(*work)
    assert named.acc is g._acc and named.f is g.f and named.tq is g.tq
    assert named.dissipated is g.dissipated and named.counts is g.counts


def test_the_opening_follows_the_field_order():
    """``granules.opening_of`` builds ``kernel.Opening`` by position: the kick's step, the rotor's
    ω only for a co-rotating floor, the effect's own counters, the log's arrays."""
    energy = np.zeros(2)
    kept = (np.zeros((3, 2)), np.zeros((3, 2)), np.zeros(3), np.zeros((4, 2)), np.zeros((1, 2)))
    named = kernel.Opening(*opening_of((FloorKick(0.25, True, energy), 7.0), kept))
    assert (named.dv_max, named.omega, named.corotating, named.keep) == (0.25, 7.0, True, True)
    assert named.energy is energy
    assert all(a is b for a, b in zip(named.kept, kept, strict=True))
    named = kernel.Opening(*opening_of((FloorKick(0.25, False, energy), 7.0), None))
    assert named.omega == 0.0 and not named.corotating and not named.keep
    named = kernel.Opening(*opening_of(None, None))
    assert named.energy.shape == (0,) and not named.keep


def test_advance_takes_named_or_plain_bundles_alike():
    """200 steps in calls of 20: ``step`` (plain tuples) and ``advance`` with named tuples give
    the same state bit for bit."""
    plain, named = _scene(), _scene()
    for _ in range(10):
        plain.step(20)
        polys, table = named.polygons, named.polygon_table
        settings, state, props, bonds, params, walls, _, nbrs, work = named._bundles(
            polys, table, 20, 0.0, math.inf, True
        )
        polygons = kernel.Polygons(
            polys.arrays(), table.arrays(), named.polygon_hist, polys.loads(),
            kernel.CandidateList(*named._listed),
        )  # fmt: skip
        named.start, named.nbr, named.hist, _, cstart, cpoly, _, _ = kernel.advance(
            kernel.Settings(*settings), kernel.Granules(*state), kernel.GranuleProps(*props),
            kernel.Bonds(*bonds), params, kernel.Walls(*walls), polygons,
            kernel.NeighbourList(*nbrs), kernel.Work(*work),
            kernel.Opening(*opening_of(None, None)),
        )  # fmt: skip
        named._listed = (cstart, cpoly, *named._listed[2:])
        named._rebuild = False
        named.steps += 20
        named.time += 20 * named.dt
    assert plain.polygon_hist[:, :, HIST_NORMAL_IMPULSE].any()  # polygon contacts happened
    for name in ("x", "v", "w", "a_prev", "f", "tq", "hist", "wall_hist", "polygon_hist"):
        np.testing.assert_array_equal(getattr(plain, name), getattr(named, name), err_msg=name)
    np.testing.assert_array_equal(plain.dissipated, named.dissipated)
    for name in ("vertices", "com", "pivot", "force", "torque", "moment"):
        a, b = getattr(plain.polygons, name), getattr(named.polygons, name)
        np.testing.assert_array_equal(a, b, err_msg=name)
