"""Whole machine steps of the soft model in one compiled call: :func:`machine_steps`, for
:meth:`perga.contact.soft.model.SoftContacts.machine_steps`.

Each step is :meth:`perga.engine.simulation.Simulation.step`'s order (that module's doc), made
of the compiled functions the Python step calls, on the same arrays, so it gives the same
floats: the machine's state read (``engine.machine.read_bodies``; a step's end state is the
next one's start, read once), the hammers posed one granule step ahead
(``machine.pose_polygons``), one kernel call (``kernel.advance``: the floor kick handed over,
the impact log's copy, the granule steps), the loads written onto the hammer bodies
(``machine.load_bodies``), Chipmunk's step and the state read again
(``engine.machine.chipmunk_step``), the energy meter (``engine.energy.meter_step``) and the pace
of coasting (``granules.pace_coasting``). What the Python step adds is left to it: the call
returns after a step in which the kernel counted a contact change or a release (the impact log
and the releases then look, in Python), or after ``limit`` steps.
"""

from __future__ import annotations

import time

from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic, overload

from perga.contact.soft import kernel
from perga.contact.soft.granules import looks_for_coasting, pace_coasting
from perga.contact.soft.machine import load_bodies, pose_polygons
from perga.machine.energy import meter_step
from perga.machine.machine import chipmunk_step, read_bodies
from perga.machine.units import ANGULAR_VELOCITY

CONTACT_CHANGES, RELEASES = kernel.COUNT_CONTACT_CHANGES, kernel.COUNT_RELEASES


def _ticks() -> int:
    """The processor's cycle counter (LLVM's ``readcyclecounter``: the TSC on x86-64), which
    costs a few nanoseconds to read, in compiled code; nanoseconds in Python (numba's JIT off)."""
    return time.perf_counter_ns()


@intrinsic
def _cycle_counter(typingctx):
    """LLVM's ``readcyclecounter``."""

    def codegen(context, builder, signature, args):
        counter = ir.FunctionType(ir.IntType(64), [])
        read = cgutils.get_or_insert_function(builder.module, counter, "llvm.readcyclecounter")
        return builder.call(read, [])

    return types.int64(), codegen


@overload(_ticks, inline="always")
def _ticks_compiled():
    return lambda: _cycle_counter()


@njit(cache=True, nogil=True)
def machine_steps(
    limit, machine, meter, pose, loads, call, opening, coasting, moment_units, watch
):  # fmt: skip
    """Take machine steps until ``limit`` are done or one ends with a change that ``watch`` =
    (contact changes, releases) asks for: the kernel's count of it differs from the call's start
    (False: not watched). Returns (steps, rebuilds, candidate lists, coasted granule steps, the
    neighbour list's start, nbr and hist, the candidate list's start and polygon, the last
    step's moment of the loads about the axis in internal angular-impulse units, the cycles
    spent in the kernel calls and in the whole loop: the kernel's share of the steps).

    machine: ``Machine.raw_step``'s, then the state tables before and after a step; meter:
    ``EnergyMeter.compiled``'s and whether to meter; pose and loads: ``MachinePolygons
    .pose_arguments`` and ``.load_arguments``; call: ``SoftGranules.call_arguments`` (its
    settings' rebuild is the first call's, first_step the first call's first step); opening:
    ``kernel.Opening`` with omega taken from each step's state when corotating; coasting:
    ``SoftGranules.coasting`` and its pacing; moment_units: the machine step, s, and the internal
    angular-impulse unit, N·m·s (the loads' moment in N·m times the one over the other)."""
    raw, before, after = machine
    meter_on, meter_args = meter
    settings, granules, props, bonds, params, walls, polygons, nbrs, work = call
    n_steps, dt, gravity, skin, drag, v_cap, pairs, rebuild, first, _ = settings
    arrays, table, hist, polygon_loads, listed = polygons
    cstart, cpoly, list_vertices, list_reach = listed
    start, nbr, pair_hist, x_ref = nbrs
    dv_max, _, corotating, energy, keep, kept = opening
    coast_on, pacing = coasting
    watch_changes, watch_releases = watch
    counts = work[4]
    changes, releases = counts[CONTACT_CHANGES], counts[RELEASES]
    addresses, cogs = raw[3], raw[4]
    rebuilds = lists = coasted = 0
    moment = 0.0
    step_time, angular_impulse = moment_units
    steps = 0
    kernel_ticks = 0
    started = _ticks()
    read_bodies(addresses, cogs, before)
    while steps < limit:
        pose_polygons(before, *pose)
        coast = looks_for_coasting(coast_on, pacing, n_steps)
        called = _ticks()
        out = kernel.advance(
            (n_steps, dt, gravity, skin, drag, v_cap, pairs, rebuild and steps == 0,
             first + steps * n_steps, coast),
            granules, props, bonds, params, walls,
            (arrays, table, hist, polygon_loads, (cstart, cpoly, list_vertices, list_reach)),
            (start, nbr, pair_hist, x_ref), work,
            (dv_max, before[0, 5] * ANGULAR_VELOCITY if corotating else 0.0, corotating, energy,
             keep, kept),
        )  # fmt: skip
        kernel_ticks += _ticks() - called
        start, nbr, pair_hist = out[0], out[1], out[2]
        cstart, cpoly = out[4], out[5]
        rebuilds += out[3]
        lists += out[6]
        coasted += out[7]
        pace_coasting(pacing, coast, out[7], granules[0].shape[0], n_steps)
        moment = load_bodies(*loads) * step_time / angular_impulse
        chipmunk_step(raw, after)
        if meter_on:
            meter_step(meter_args, before, after, moment)
        steps += 1
        if (watch_changes and counts[CONTACT_CHANGES] != changes) or (
            watch_releases and counts[RELEASES] != releases
        ):
            break
        before, after = after, before  # nothing moves the bodies between two steps
    ticks = _ticks() - started
    return (
        steps, rebuilds, lists, coasted, start, nbr, pair_hist, cstart, cpoly, moment,
        kernel_ticks, ticks,
    )  # fmt: skip
