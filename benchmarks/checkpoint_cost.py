"""What a checkpoint costs (issue 15, item 4): for bundled cases after ``--steps`` steps, the
checkpoint's size and the median time to pickle it (``checkpoints.dump``), to write it (a
temporary file, fsync, rename, fsync of the directory) and to read it back
(``checkpoints.read``: unpickle and restore Chipmunk's raw state), against the time of one
machine step; so the share of the run a checkpoint every ``output.checkpoint_every`` costs.

    python benchmarks/checkpoint_cost.py
    python benchmarks/checkpoint_cost.py --cases separator soft-separator --repeats 9
    python benchmarks/checkpoint_cost.py --runs 3 --cases separator soft-separator

With ``--runs N``: N interleaved pairs of whole ``perga run``s of each case, without checkpoints
(``output.checkpoint_every = 0``) and with the default grid, each a process of its own: the
median wall time (summary.json) and the median peak memory (the process's maximum RSS).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case
from perga.run import checkpoints

CASES = ("separator", "soft-separator", "plate-hammers-soft", "bee-bread-separator")


def median_time(action, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def whole_run(case: str, out: Path, every: str) -> tuple[float, float]:
    """(wall s from summary.json, peak RSS MB) of one ``perga run`` of ``case``."""
    command = [sys.executable, "-m", "perga.cli", "run", f"cases/{case}.toml", "-o", str(out),
               "--overwrite", "--quiet", "--set", f"output.checkpoint_every={every}"]  # fmt: skip
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    assert proc.returncode == 0, command
    wall = json.loads((out / "summary.json").read_text())["wall_time"]
    return wall, usage.ru_maxrss / 1024


def runs(cases: list[str], pairs: int) -> None:
    """The whole-run comparison of the module doc."""
    print("case | without: wall s, peak MB | every 0.1 s: wall s, peak MB | cost")
    with tempfile.TemporaryDirectory() as scratch:
        for name in cases:
            got: dict[str, list[tuple[float, float]]] = {"0": [], "0.1": []}
            for _ in range(pairs):
                for every in got:
                    got[every].append(whole_run(name, Path(scratch) / "run", every))
            (w0, m0), (w1, m1) = (
                (statistics.median(x for x, _ in got[e]), statistics.median(y for _, y in got[e]))
                for e in got
            )
            print(f"{name} | {w0:.2f}, {m0:.0f} | {w1:.2f}, {m1:.0f} | {w1 / w0 - 1:+.1%}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", nargs="+", default=CASES)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--runs", type=int, default=0, help="pairs of whole runs (module doc)")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    if args.runs:
        runs(args.cases, args.runs)
        return
    print(f"medians of {args.repeats}")
    print("case | granules | size, MB | pickle, ms | write, ms | read, ms | step, ms | "
          "cost of one at checkpoint_every = 0.1 s, % of the run")  # fmt: skip
    with tempfile.TemporaryDirectory() as scratch:
        run = Path(scratch)
        for name in args.cases:
            case = load_case(Path("cases") / f"{name}.toml")
            sim = Simulation(compile_case(case))
            with sim.running():
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
