"""The share of a run's wall time that its ParaView output costs: whole `perga run`s of a case
with the default ``output.record`` and with 'vtk' left out, interleaved run by run, each in a
fresh process; optionally side by side with another commit (``--against REF``, checked out in
a temporary worktree). The share of a pair is 1 - (wall without vtk) / (wall with vtk), both
from ``summary.json``; figures are medians over ``--repeats`` with the spread (min-max).

With ``--against`` the ParaView files of the two trees' runs are compared byte for byte.

    python benchmarks/output_share.py                                  # soft separator, 0.2 s
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
from pathlib import Path

from trees import worktree

ROOT = Path(__file__).resolve().parents[1]
NO_VTK = 'output.record=["granules", "hammers", "impacts", "energy"]'


def run(src: Path, case: Path, seconds: float, out: Path, vtk: bool) -> float:
    """One ``perga run`` of ``case`` from the tree ``src`` into ``out``: its wall time, s."""
    sets = ["--set", f"solver.duration={seconds}"] + ([] if vtk else ["--set", NO_VTK])
    command = [sys.executable, "-m", "perga.cli", "run", str(case), "-o", str(out), "--overwrite",
               "--quiet", *sets]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(src)}
    subprocess.run(command, check=True, capture_output=True, env=env, cwd=src.parent)
    return json.loads((out / "summary.json").read_text())["wall_time"]


def digest(folder: Path) -> str:
    """SHA-256 over the ParaView files of a run (names and bytes, sorted by name)."""
    sha = hashlib.sha256()
    for path in sorted((folder / "vtk").glob("*")):
        if path.suffix in (".vtu", ".pvd"):
            sha.update(path.name.encode() + path.read_bytes())
    return sha.hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", type=Path, default=ROOT / "cases" / "soft-separator.toml")
    parser.add_argument("--seconds", type=float, default=0.2, help="simulated time, s")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--against", help="a commit to run side by side")
    args = parser.parse_args()
    trees = {"this tree": ROOT / "src"}
    if args.against:
        trees[args.against] = worktree(args.against)
    case = args.case.resolve()
    print(f"{case.name}, {args.seconds} s simulated, {args.repeats} repeats, "
          f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        walls: dict[str, dict[bool, list[float]]] = {t: {True: [], False: []} for t in trees}
        for src in trees.values():  # numba's cache, untimed
            run(src, case, args.seconds, Path(tmp) / "warm", True)
        for _ in range(args.repeats):
            for name, src in trees.items():
                for vtk in (True, False):
                    out = Path(tmp) / f"{hash(name)}-{vtk}"
                    walls[name][vtk].append(run(src, case, args.seconds, out, vtk))
        print(f"{'tree':>12s} {'with vtk s':>11s} {'without s':>10s} {'vtk share':>10s} (min-max)")
        for name in trees:
            w, wo = walls[name][True], walls[name][False]
            shares = [1 - b / a for a, b in zip(w, wo, strict=True)]
            print(f"{name:>12s} {statistics.median(w):11.2f} {statistics.median(wo):10.2f} "
                  f"{100 * statistics.median(shares):9.1f} % ({100 * min(shares):.1f}-"
                  f"{100 * max(shares):.1f})")  # fmt: skip
        if args.against:
            ratios = [a / b for a, b in zip(*(walls[t][True] for t in trees), strict=True)]
            print(f"wall with vtk, this tree / {args.against}: {statistics.median(ratios):.3f} "
                  f"({min(ratios):.3f}-{max(ratios):.3f})")  # fmt: skip
            digests = {t: digest(Path(tmp) / f"{hash(t)}-True") for t in trees}
            print(f"ParaView files byte-identical: {len(set(digests.values())) == 1} {digests}")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
