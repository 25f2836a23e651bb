"""What one output frame costs, recorder by recorder (issue 14, item 4): a case run to
``--start`` s, then ``--frames`` frames, each after ``--steps`` machine steps, every recorder of
the case's ``output.record`` timed on each; medians, ms per frame, one thread.

    python benchmarks/frame_cost.py                            # the soft separator
    python benchmarks/frame_cost.py cases/separator.toml
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case
from perga.output.recorders import make_recorders
from perga.output.scene_file import write_scene

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", nargs="?", default=str(ROOT / "cases/soft-separator.toml"))
    parser.add_argument("--start", type=float, default=0.1, help="simulated s before timing")
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--steps", type=int, default=10, help="machine steps between frames")
    args = parser.parse_args()
    case = load_case(args.case, overrides=["solver.threads=1"])
    spec = compile_case(case)
    sim = Simulation(spec, record_impacts=True, track_energy=True)
    sim.run(args.start)
    times: dict[str, list[float]] = {}

    def timed(name: str, call, *call_args, **kwargs):
        start = time.perf_counter()
        out = call(*call_args, **kwargs)
        times.setdefault(name, []).append(time.perf_counter() - start)
        return out

    with tempfile.TemporaryDirectory() as out:
        write_scene(Path(out), spec)
        recorders = make_recorders(case.output.record, Path(out), spec, case.output.granule_table)
        with sim.running():
            for _ in range(args.frames):
                sim.run(args.steps * sim.dt)
                frame = timed("Simulation.frame", sim.frame, contacts="vtk" in case.output.record)
                events = sim.events()
                for recorder in recorders:
                    timed(type(recorder).__name__, recorder.record, frame, events)
        for recorder in recorders:
            recorder.close()
    print(f"{args.case}: {args.frames} frames from t = {args.start} s, load "
          f"{os.getloadavg()[0]:.2f}")  # fmt: skip
    for name, values in times.items():
        print(f"{name:>20} {1e3 * statistics.median(values):7.3f} ms per frame (median)")
    total = sum(statistics.median(v) for v in times.values())
    print(f"{'all':>20} {1e3 * total:7.3f} ms per frame")


if __name__ == "__main__":
    main()
