"""Every bundled scene run whole in this tree and in another commit, and their outputs compared
byte for byte: every table, ParaView series (``.pvd``) and frame (``.vtu``), scene.json, the
case copy, and summary.json but for what a run measures of itself or takes from where it ran
(wall time, steps per second, the case's path, the threads used); ``trajectories.vtu`` whose
bytes differ is compared line by line (:mod:`trajectory_lines`: its points' order changed).

Both trees run the same case files (this tree's ``cases/``) in a fresh subprocess each
(``perga run``, the other tree's ``src/`` first on the path), one after the other.

    python benchmarks/same_results.py --against HEAD~3            # every bundled scene, whole
    python benchmarks/same_results.py --against HEAD~3 --cases separator soft-separator
    python benchmarks/same_results.py --against HEAD~3 --seconds 0.05   # a shorter run of each
    python benchmarks/same_results.py --against HEAD~3 --keep runs/same  # keep the runs: then
    python benchmarks/compare_runs.py runs/same/separator/this runs/same/separator/other
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from trajectory_lines import same_lines
from trees import worktree

ROOT = Path(__file__).resolve().parents[1]
MEASURED = ("wall_time", "steps_per_second", "case", "threads")
"""summary.json fields a run measures of itself or takes from where it ran."""


def scenes() -> list[Path]:
    """The bundled cases that are scenes (with a [chamber]), not parameter sets."""
    return [p for p in sorted((ROOT / "cases").glob("*.toml"))
            if "chamber" in tomllib.loads(p.read_text(encoding="utf-8"))]  # fmt: skip


def run(source: Path, case: Path, out: Path, seconds: float | None) -> float:
    """``perga run case -o out`` with ``source`` (a src/ folder) first on the path; wall s."""
    sets = [] if seconds is None else ["--set", f"solver.duration={seconds!r}"]
    env = {**os.environ, "PYTHONPATH": str(source)}
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "perga.cli", "run", str(case), "-o", str(out), "--quiet",
         "--overwrite", *sets],
        env=env, capture_output=True, text=True, cwd=ROOT,
    )  # fmt: skip
    if done.returncode not in (0, 3):
        raise RuntimeError(f"{case.name} with {source}: exit {done.returncode}\n{done.stderr}")
    return time.perf_counter() - start


def outputs(run: Path) -> set[str]:
    """The run's files but its checkpoints (which pickle the run's own paths)."""
    return {str(p.relative_to(run)) for p in run.rglob("*")
            if p.is_file() and "checkpoints" not in p.relative_to(run).parts}  # fmt: skip


def differences(a: Path, b: Path) -> list[str]:
    """The files of run ``a`` that are not byte for byte those of run ``b`` (summary.json:
    its fields but :data:`MEASURED`; trajectories.vtu: its lines), and the files only one of
    them has; checkpoints, which pickle the run's own paths, are not compared."""
    files, others = outputs(a), outputs(b)
    out = [f"{f} (only in one)" for f in sorted(files ^ others)]
    for name in sorted(files & others):
        if name == "summary.json":
            sa, sb = (json.loads((r / name).read_text(encoding="utf-8")) for r in (a, b))
            for s in (sa, sb):
                for key in MEASURED:
                    s.pop(key, None)
            if sa != sb:
                keys = sorted(k for k in sa.keys() | sb.keys() if sa.get(k) != sb.get(k))
                out.append(f"summary.json ({', '.join(keys)})")
        elif not filecmp.cmp(a / name, b / name, shallow=False):
            lines_alike = name.endswith("trajectories.vtu") and same_lines(a / name, b / name)
            if not lines_alike:
                out.append(name)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", required=True, help="the git ref to compare with")
    parser.add_argument("--cases", nargs="+", help="case names (default: every bundled scene)")
    parser.add_argument("--seconds", type=float, help="simulated seconds of every case")
    parser.add_argument("--keep", type=Path, help="keep the runs in DIR/CASE/{this,other}")
    args = parser.parse_args()
    cases = [c for c in scenes() if args.cases is None or c.stem in args.cases]
    other = worktree(args.against)
    print(f"this tree against {args.against}; load average {os.getloadavg()[0]:.2f}")
    same = 0
    with tempfile.TemporaryDirectory() as scratch:
        work = args.keep or Path(scratch)
        for case in cases:
            mine, theirs = work / case.stem / "this", work / case.stem / "other"
            wall_mine = run(ROOT / "src", case, mine, args.seconds)
            wall_theirs = run(other, case, theirs, args.seconds)
            differ = differences(mine, theirs)
            files = len(outputs(mine))
            verdict = "same bytes" if not differ else "DIFFER: " + ", ".join(differ[:6])
            same += not differ
            print(f"{case.stem:>22}: {files:4d} files, {verdict} "
                  f"({wall_mine:.1f} s, {wall_theirs:.1f} s)", flush=True)  # fmt: skip
    print(f"{same} of {len(cases)} cases write the same bytes")
    sys.exit(0 if same == len(cases) else 1)


if __name__ == "__main__":
    main()
