"""Issue 15's must-show for checkpoints: SIGINT, SIGTERM and SIGKILL sent to ``perga run`` at
random moments (seeded), then ``perga run --resume``, ``--trials`` times each on the rigid and
the soft separator; every stopped run must read back whole (tests/test_faults.py's
``assert_readable``) and every resumed run must end with the tables and ParaView frames of a
run that never stopped, byte for byte (``summary.json``, which counts wall time and
resumptions, and the checkpoints themselves excepted).

The moment is drawn uniformly from the run's first checkpoint (written at t = 0, after the
build) to the end of the uninterrupted run's wall time, so that every trial has something to
resume from; a signal that lands after the end, or as the completed process exits, is counted
as "ended first", and trials go on until ``--trials`` runs were stopped and resumed. Signals
during start-up are tests/test_faults.py's. With ``--geometry`` the cases are instead every
bundled case with a geometry file, shortened as tests/test_resume_geometry.py does. Do not
edit perga while this runs: a checkpoint is read only by the code that wrote it.

    python benchmarks/kill_resume.py                  # 20 trials each: ~40 min on 2 cores
    python benchmarks/kill_resume.py --trials 2       # a smoke run
    python benchmarks/kill_resume.py --geometry --trials 2
"""

from __future__ import annotations

import argparse
import filecmp
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.run_files import outputs
from tests.test_faults import assert_readable
from tests.test_resume_geometry import GEOMETRY_CASES

CASES = {
    "rigid": ("cases/separator.toml", ["solver.duration=0.3", "output.checkpoint_every=0.02"]),
    "soft": ("cases/soft-separator.toml", ["solver.duration=0.15", "output.checkpoint_every=0.01"]),
}
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)


def command(case: str, out: Path, sets: list[str]) -> list[str]:
    overrides = [a for s in sets for a in ("--set", s)]
    return [sys.executable, "-m", "perga.cli", "run", case, "-o", str(out), "--quiet", *overrides]


def identical(run: Path, reference: Path) -> bool:
    files = outputs(reference)
    return outputs(run) == files and all(filecmp.cmp(run / f, reference / f, False) for f in files)


def first_checkpoint(out: Path, proc: subprocess.Popen[bytes]) -> float:
    """Wait for the run's first checkpoint file; returns when it appeared (time.monotonic)."""
    while not list((out / "checkpoints").glob("step-*.ckpt")):
        if proc.poll() is not None:
            raise RuntimeError(f"{out}: the run ended without a checkpoint")
        time.sleep(0.01)
    return time.monotonic()


def trial(case: str, sets: list[str], reference: Path, out: Path, signum: int, delay: float) -> str:
    """One stop ``delay`` s after the run's first checkpoint, and its resumption: the
    outcome's name."""
    proc = subprocess.Popen(command(case, out, sets), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)  # fmt: skip
    first_checkpoint(out, proc)
    time.sleep(delay)
    proc.send_signal(signum)
    if proc.wait(timeout=300) == 0:
        return "ended first"
    summary = out / "summary.json"
    if summary.exists() and json.loads(summary.read_text())["status"] == "completed":
        return "ended first"  # the signal came as the process was exiting
    if signum != signal.SIGKILL:
        assert_readable(out)  # a killed run has no summary.json until it is resumed
    resumed = subprocess.run(
        [sys.executable, "-m", "perga.cli", "run", "--resume", str(out), "--quiet"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    if resumed.returncode != 0:
        return f"resume failed: {resumed.stderr.strip()[-200:]}"
    assert_readable(out)
    return "identical" if identical(out, reference) else "DIFFERENT"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--trials", type=int, default=20, help="stopped and resumed runs per signal and engine"
    )
    parser.add_argument("--seed", type=int, default=15)
    parser.add_argument("--engines", nargs="+", choices=list(CASES), default=list(CASES))
    parser.add_argument(
        "--geometry",
        action="store_true",
        help="the bundled cases with a geometry file instead of the separators (--engines)",
    )
    args = parser.parse_args()
    cases = (
        {Path(n).stem: (f"cases/{n}", sets) for n, sets in GEOMETRY_CASES.items()}
        if args.geometry
        else {engine: CASES[engine] for engine in args.engines}
    )
    rng = random.Random(args.seed)
    print(f"load average at start: {os.getloadavg()[0]:.2f}; {args.trials} trials each")
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        for engine, (case, sets) in cases.items():
            for warm in (True, False):  # the first run fills numba's cache (compiling)
                reference = root / f"{engine}-reference-{warm}"
                proc = subprocess.Popen(command(case, reference, sets))
                start = first_checkpoint(reference, proc)
                assert proc.wait() == 0
                span = time.monotonic() - start  # from the first checkpoint to the end
            for signum in SIGNALS:
                outcomes: Counter[str] = Counter()
                for k in range(3 * args.trials):  # until --trials stopped runs were resumed
                    if k - outcomes["ended first"] == args.trials:
                        break
                    out = root / f"{engine}-{signum}-{k}"
                    delay = rng.uniform(0.0, span)
                    outcomes[trial(case, sets, reference, out, signum, delay)] += 1
                    shutil.rmtree(out, ignore_errors=True)
                name = signal.Signals(signum).name
                counts = ", ".join(f"{n} {what}" for what, n in sorted(outcomes.items()))
                print(f"{engine:5s} {name:7s} ({span:.1f} s after the first checkpoint): {counts}",
                      flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
