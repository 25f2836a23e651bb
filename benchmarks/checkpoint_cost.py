"""What a checkpoint costs (issue 15, item 4): for bundled cases after ``--steps`` steps, the
checkpoint's size and the median time to pickle it (``checkpoints.dump``), to write it (a
temporary file, fsync, rename, fsync of the directory) and to read it back
(``checkpoints.read``: unpickle and restore Chipmunk's raw state), against the time of one
machine step; so the share of the run a checkpoint every ``output.checkpoint_every`` costs.

    python benchmarks/checkpoint_cost.py
    python benchmarks/checkpoint_cost.py --cases separator soft-separator --repeats 9
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from perga import checkpoints
from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.from_case import scene_spec

CASES = ("separator", "soft-separator", "plate-hammers-soft", "bee-bread-separator")


def median_time(action, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", nargs="+", default=CASES)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}; medians of {args.repeats}")
    print("case | granules | size, MB | pickle, ms | write, ms | read, ms | step, ms | "
          "cost of one at checkpoint_every = 0.1 s, % of the run")  # fmt: skip
    with tempfile.TemporaryDirectory() as scratch:
        run = Path(scratch)
        for name in args.cases:
            case = load_case(Path("cases") / f"{name}.toml")
            sim = Simulation(scene_spec(case))
            with sim.contacts.running():
                for _ in range(args.steps):
                    sim.step()
                step = median_time(sim.step, 200)
            data = checkpoints.dump(sim, {}, run, "case")
            pickle_s = median_time(
                lambda sim=sim: checkpoints.dump(sim, {}, run, "case"), args.repeats
            )
            write_s = median_time(
                lambda data=data, sim=sim: checkpoints.write(run, sim.steps, data), args.repeats
            )
            read_s = median_time(lambda data=data: checkpoints.read(data), args.repeats)
            steps_between = 0.1 / sim.dt
            share = (pickle_s + write_s + read_s) / (steps_between * step)
            granules = len(sim.contacts.granule_state().ids)
            print(f"{name} | {granules} | {len(data) / 1e6:.2f} | {pickle_s * 1e3:.1f} | "
                  f"{write_s * 1e3:.1f} | {read_s * 1e3:.1f} | {step * 1e3:.3f} | "
                  f"{100 * share:.2f}")  # fmt: skip


if __name__ == "__main__":
    main()
