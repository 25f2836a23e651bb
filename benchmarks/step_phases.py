"""Where a machine step's time goes, phase by phase (issue 14): the step of
``perga.engine.simulation.Simulation.step`` taken apart in its documented order, each phase
timed, over ``--steps`` steps after ``--start`` s of the case, one thread. Before timing, the
script checks on a second build that its copy of the order moves the simulation exactly as
``Simulation.step`` does (bit-identical granule positions after 200 steps), so the phases are
those of the real step (the kernel's phase includes the floor-friction kick and the impact
log's copy of the state, which the kernel call makes first). Compiled code first needed inside
the timed window (the impact log's scan runs only after a step that opened or closed a contact)
compiles there on the first run after numba's cache was cleared: run it twice after changing
compiled code. These are the phases of ``Simulation.step``, the step taken one at a time; a run
of the soft model takes its steps compiled, several at once, where the case allows
(``Simulation.advance``), and ``benchmarks/separator_speed.py`` times those.

    python benchmarks/step_phases.py                                 # the soft separator
    python benchmarks/step_phases.py cases/separator.toml --start 0.15
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from perga.case import load_case
from perga.contact.soft.model import ANGULAR_IMPULSE
from perga.engine.simulation import Simulation
from perga.machine import units as u
from perga.model.compile import compile_case

ROOT = Path(__file__).resolve().parents[1]


def phased_step(sim: Simulation, timers: dict[str, float]) -> None:
    """One step of ``sim`` in Simulation.step's order, each phase's time added to ``timers``."""

    def timed(name: str, call, *args):
        start = time.perf_counter()
        out = call(*args)
        timers[name] = timers.get(name, 0.0) + time.perf_counter() - start
        return out

    c = sim.contacts
    end = (sim.steps + 1) * sim.dt
    if sim.kicks is not None:
        timed("kicks", sim.kicks.run, sim.dt)
    before = timed("machine reads", sim.machine.state)
    if hasattr(c, "polygons"):  # soft: the parts of before_machine_step
        timed("pose", c.polygons.pose, c.granule_dt, before)
        kept = None if c.log is None else timed("impact log", c.log.kept)
        floor = None if c.floor is None else (c.floor, before.table[0, 5] * u.ANGULAR_VELOCITY)
        timed("kernel", lambda: c.granules.step(c.substeps, floor=floor, kept=kept))
        moment = timed("loads", c.polygons.apply_loads)
        c._moment = moment * c._machine_dt / ANGULAR_IMPULSE
    else:
        timed("contacts before", c.before_machine_step, end, before)
    if sim.meter is not None:
        timed("meter", sim.meter.before_step, before)
    timed("Chipmunk", sim.machine.space.step, sim._dt_internal)
    after = timed("machine reads", sim.machine.state)
    moment = timed("contacts after", c.after_machine_step, end, after)
    if sim.meter is not None:
        timed("meter", sim.meter.after_step, sim._dt_internal, moment, after)
    sim.steps += 1
    timed("process", sim._process, end)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases/soft-separator.toml"))
    parser.add_argument("--start", type=float, default=0.15, help="simulated s before timing")
    parser.add_argument("--steps", type=int, default=3000)
    args = parser.parse_args()
    spec = compile_case(load_case(args.case, overrides=["solver.threads=1"]))
    reference, copy = Simulation(spec), Simulation(spec)
    for _ in range(200):
        reference.step()
        phased_step(copy, {})
    same = np.array_equal(reference.frame().granules.positions, copy.frame().granules.positions)
    if not same:
        raise SystemExit("the phased copy of the step no longer matches Simulation.step")
    sim = Simulation(spec)
    sim.run(args.start)
    timers: dict[str, float] = {}
    with sim.running():  # as perga run holds it
        for _ in range(args.steps):
            phased_step(sim, timers)
    total = sum(timers.values())
    print(f"{args.case}: {args.steps} steps from t = {args.start} s, load "
          f"{os.getloadavg()[0]:.2f}; the phased step matches Simulation.step: {same}")  # fmt: skip
    for name, seconds in sorted(timers.items(), key=lambda kv: -kv[1]):
        share = 100 * seconds / total
        print(f"{name:>16} {1e6 * seconds / args.steps:8.1f} µs/step {share:5.1f} %")
    kernel = timers.get("kernel", 0.0)
    print(f"{'step':>16} {1e6 * total / args.steps:8.1f} µs/step; outside the kernel "
          f"{100 * (1 - kernel / total):.0f} %")  # fmt: skip


if __name__ == "__main__":
    main()
