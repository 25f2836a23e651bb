"""Issue 5: cost of writing one VTK frame (``perga.output.vtk.VtkRecorder.record``: granules
and machine ``.vtu`` plus both ``.pvd``) of 10,000 granules against the simulation time between
frames at the default cadence (output.every = 1e-3 s). Requirement: ratio < 10 %.

Scene: the rigid one of ``engine_vs_pymunk.py`` (rotor, 6 hinged hammers, chamber, granule
collisions, dt = its DT) with 10,000 granules, after 20 steps. Reported: median step and frame
write times (wall s), steps per frame = every / dt, and write / (steps per frame × step).

    python benchmarks/vtk_writer.py                      # ~30 s
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from perga.engine import Simulation
from perga.output.vtk import VtkRecorder

sys.path.insert(0, str(Path(__file__).parent))
from engine_vs_pymunk import perga_spec


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--granules", type=int, default=10_000)
    p.add_argument("--every", type=float, default=1e-3, help="frame interval, s")
    p.add_argument("--steps", type=int, default=20, help="timed steps")
    p.add_argument("--frames", type=int, default=20, help="timed frame writes")
    args = p.parse_args(argv)
    sim = Simulation(
        perga_spec(args.granules, chamber=True), record_impacts=True, track_energy=True
    )
    for _ in range(20):
        sim.step()
    steps = []
    for _ in range(args.steps):
        t0 = time.perf_counter()
        sim.step()
        steps.append(time.perf_counter() - t0)
    with tempfile.TemporaryDirectory() as directory:
        recorder = VtkRecorder(Path(directory), sim.spec)
        recorder.record(sim.frame(), sim.impacts)  # first frame: chamber, imports
        writes = []
        for _ in range(args.frames):
            sim.step()
            t0 = time.perf_counter()
            recorder.record(sim.frame(), sim.impacts)
            writes.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        recorder.close()
        close = time.perf_counter() - t0
    step, write = statistics.median(steps), statistics.median(writes)
    per_frame = args.every / sim.dt
    print(f"granules {args.granules}, dt {sim.dt:.3g} s, every {args.every:g} s")
    print(f"step (impacts + energy on): {1e3 * step:.2f} ms; steps per frame {per_frame:.1f}")
    print(f"simulation between frames: {per_frame * step:.3f} s")
    print(f"frame write: {1e3 * write:.1f} ms (median of {args.frames})")
    print(f"ratio write / simulation: {write / (per_frame * step):.2%} (required < 10 %)")
    print(f"close ({args.frames + 1} frames of trajectories, impacts): {1e3 * close:.0f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
