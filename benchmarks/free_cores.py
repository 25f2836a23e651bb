"""The free cores as the one-minute load average counts them and as ``perga.cores`` measures
them, while a job holds a core and after it ends (issue 14, item 3).

A child process spins on one core for ``--busy`` seconds; the two counts are printed at times
during and after it. The load average counts the job from a minute before it is gone, and keeps
counting it for a minute after: a soft run started then, whose kernel could take a second
core, is held to one thread.

    python benchmarks/free_cores.py                # ~1 min
    python benchmarks/free_cores.py --busy 30
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import time

from perga.cores import CoreMonitor, allowed_cores


def spin(seconds: float) -> None:
    """Keep one core busy for ``seconds``."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        pass


def counts() -> tuple[int, float, int]:
    """(free cores by the load average, the load average, free cores measured over 0.1 s)."""
    load = os.getloadavg()[0]
    return max(1, len(allowed_cores()) - round(load)), load, CoreMonitor().free()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--busy", type=float, default=20.0, help="seconds the job spins")
    args = parser.parse_args()
    print(f"cores allowed: {len(allowed_cores())}; a job spins on one core for {args.busy:g} s")
    print(f"{'when':>28} {'load avg':>9} {'free (load avg)':>16} {'free (measured)':>16}")
    job = multiprocessing.Process(target=spin, args=(args.busy,))
    start = time.monotonic()
    marks = [("before the job", None)]
    marks += [(f"job running, {t:g} s in", t) for t in (2.0, args.busy - 2.0)]
    marks += [(f"job ended {t:g} s ago", args.busy + t) for t in (1.0, 10.0, 30.0)]
    for label, at in marks:
        if at is None:
            free_load, load, measured = counts()
            job.start()
            start = time.monotonic()
        else:
            time.sleep(max(0.0, start + at - time.monotonic()))
            free_load, load, measured = counts()
        print(f"{label:>28} {load:9.2f} {free_load:16d} {measured:16d}")
    job.join()


if __name__ == "__main__":
    main()
