"""The run's own time spent on its ParaView output, measured inside the run: the granules'
contact counts (which only the ParaView frames carry), handing each frame and its events to
the writer process (``WriterProcess.record``: pickling and the pipe), and waiting at the end
for the writer to finish (``WriterProcess.close``: the last frames, ``trajectories.vtu``,
``impacts.vtu``). Each is the sum of ``time.perf_counter`` around the calls; the share is their
sum over the wall time of the whole ``simulate`` call. Runs of one process after an untimed
one (numba's cache, imports); medians with the spread (min-max).

    python benchmarks/output_main_time.py                       # soft separator, 0.5 s
    python benchmarks/output_main_time.py --repeats 9 --case cases/bee-bread-separator.toml
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from call_timer import timed

from perga.contact.soft.granules import SoftGranules
from perga.output.writer_process import WriterProcess
from perga.run import simulate

ROOT = Path(__file__).resolve().parents[1]
PARTS = {
    "contact counts": (SoftGranules, "contact_counts"),
    "frames to the writer": (WriterProcess, "record"),
    "waiting at close": (WriterProcess, "close"),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=ROOT / "cases" / "soft-separator.toml")
    parser.add_argument("--seconds", type=float, default=0.5, help="simulated time, s")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    spent = dict.fromkeys(PARTS, 0.0)
    for part, (cls, name) in PARTS.items():
        setattr(cls, name, timed(spent, part, getattr(cls, name)))
    print(f"{args.case.name}, {args.seconds} s simulated, {args.repeats} repeats, "
          f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")  # fmt: skip
    runs: list[dict[str, float]] = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.repeats + 1):
            for part in spent:
                spent[part] = 0.0
            start = time.perf_counter()
            sets = [f"solver.duration={args.seconds}"]
            simulate(args.case, Path(tmp) / "run", overrides=sets, overwrite=True)
            if k:  # the first is untimed
                runs.append({**spent, "wall": time.perf_counter() - start})
    for part in [*PARTS, "wall"]:
        values = [r[part] for r in runs]
        print(f"{part:>22s} {statistics.median(values):7.3f} s "
              f"({min(values):.3f}-{max(values):.3f})")  # fmt: skip
    shares = [sum(r[p] for p in PARTS) / r["wall"] for r in runs]
    print(f"{'ParaView share':>22s} {100 * statistics.median(shares):7.1f} % "
          f"({100 * min(shares):.1f}-{100 * max(shares):.1f})")  # fmt: skip
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
