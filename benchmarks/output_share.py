"""The share of a run's wall time that its ParaView output costs: runs of a case with the default
``output.record`` and with 'vtk' left out, alternating, in one process per tree (after one
untimed pair: numba's cache, imports); optionally a second tree, another commit (``--against
REF``, checked out in a temporary worktree), measured the same way right after. The share of a
pair is 1 - (wall without vtk) / (wall with vtk), each the wall time of the whole ``simulate``
call (the run and its closing, in which the last ParaView files are written: ``summary.json``'s
``wall_time`` stops before the closing); figures are medians over ``--repeats`` with the spread
(min-max). Fresh processes per run were tried first: their
wall times spread by ±20 % on this machine, more than the share measured.

With ``--against`` the ParaView files of the two trees' runs are compared byte for byte, and
``trajectories.vtu`` line by line where its bytes differ (:mod:`trajectory_lines`).

    python benchmarks/output_share.py                                  # soft separator, 0.5 s
    python benchmarks/output_share.py --against HEAD~1 --repeats 5
    python benchmarks/output_share.py --case cases/separator.toml --seconds 0.2
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from trajectory_lines import same_lines
from trees import worktree

ROOT = Path(__file__).resolve().parents[1]
NO_VTK = 'output.record=["granules", "hammers", "impacts", "energy"]'


def pairs(case: Path, seconds: float, repeats: int, out: Path) -> None:
    """In this process: an untimed pair, then ``repeats`` pairs of runs (with vtk, without);
    prints their wall times, s, as JSON."""
    from perga.run import simulate

    def wall(vtk: bool) -> float:
        sets = [f"solver.duration={seconds}"] + ([] if vtk else [NO_VTK])
        folder = out / ("vtk" if vtk else "no-vtk")
        start = time.perf_counter()
        simulate(case, folder, overrides=sets, overwrite=True)
        return time.perf_counter() - start

    wall(True), wall(False)
    print(json.dumps([(wall(True), wall(False)) for _ in range(repeats)]))


def measured(src: Path, case: Path, seconds: float, repeats: int, out: Path) -> list[list[float]]:
    """:func:`pairs` run by the tree ``src`` in a process of its own."""
    command = [sys.executable, __file__, "--pairs", str(out), "--case", str(case),
               "--seconds", str(seconds), "--repeats", str(repeats)]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(src)}
    done = subprocess.run(command, check=True, capture_output=True, text=True, env=env)
    return json.loads(done.stdout.strip().splitlines()[-1])


def digest(folder: Path) -> str:
    """SHA-256 over the ParaView files of a run but ``trajectories.vtu`` (names and bytes,
    sorted by name)."""
    sha = hashlib.sha256()
    for path in sorted((folder / "vtk").glob("*")):
        if path.suffix in (".vtu", ".pvd") and path.name != "trajectories.vtu":
            sha.update(path.name.encode() + path.read_bytes())
    return sha.hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=ROOT / "cases" / "soft-separator.toml")
    parser.add_argument("--seconds", type=float, default=0.5, help="simulated time, s")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--against", help="a commit to run side by side")
    parser.add_argument("--pairs", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    case = args.case.resolve()
    if args.pairs:
        pairs(case, args.seconds, args.repeats, args.pairs)
        return
    trees = {"this tree": ROOT / "src"}
    if args.against:
        trees[args.against] = worktree(args.against)
    print(f"{case.name}, {args.seconds} s simulated, {args.repeats} repeats, "
          f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        walls = {
            name: measured(src, case, args.seconds, args.repeats, Path(tmp) / str(k))
            for k, (name, src) in enumerate(trees.items())
        }
        print(f"{'tree':>12s} {'with vtk s':>11s} {'without s':>10s} {'vtk share':>10s} "
              "(min-max)")  # fmt: skip
        for name, runs in walls.items():
            w, wo = [a for a, _ in runs], [b for _, b in runs]
            shares = [1 - b / a for a, b in runs]
            print(f"{name:>12s} {statistics.median(w):11.2f} {statistics.median(wo):10.2f} "
                  f"{100 * statistics.median(shares):9.1f} % ({100 * min(shares):.1f}-"
                  f"{100 * max(shares):.1f})")  # fmt: skip
        if args.against:
            this, other = ([a for a, _ in walls[t]] for t in trees)
            print(
                f"wall with vtk, this tree / {args.against}: "
                f"{statistics.median(this) / statistics.median(other):.3f} (medians)"
            )
            runs = [Path(tmp) / str(k) / "vtk" for k in range(2)]
            digests = {t: digest(run) for t, run in zip(trees, runs, strict=True)}
            same = len(set(digests.values())) == 1
            print(f"ParaView files but trajectories.vtu byte-identical: {same} {digests}")
            a, b = (run / "vtk" / "trajectories.vtu" for run in runs)
            print(f"trajectories.vtu byte-identical: {a.read_bytes() == b.read_bytes()}, "
                  f"same lines: {same_lines(a, b)}")  # fmt: skip
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
