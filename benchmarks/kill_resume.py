"""Issue 15's must-show for checkpoints: SIGINT, SIGTERM and SIGKILL sent to ``perga run`` at
random moments (seeded), then ``perga run --resume``, ``--trials`` times each on the rigid and
the soft separator; every stopped run must read back whole (tests/test_faults.py's
``assert_readable``) and every resumed run must end with the tables and ParaView frames of a
run that never stopped, byte for byte (``summary.json``, which counts wall time and
resumptions, and the checkpoints themselves excepted).

The moment is drawn from start-up (the interpreter, the imports, the build) to the end of the
uninterrupted run's wall time; a signal that lands before the run directory holds its case is
counted as "stopped before the run began", one before the first checkpoint (at t = 0, after the
build) as "no checkpoint yet" (``--resume`` then says so, exit 2), one after the end as "ended
first" (also when it lands as the completed process exits: the summary says completed).
Do not edit perga while this runs: a checkpoint is read only by the code that wrote it.

    python benchmarks/kill_resume.py                  # 20 trials each: ~25 min on 2 cores
    python benchmarks/kill_resume.py --trials 2       # a smoke run
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

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_faults import assert_readable

CASES = {
    "rigid": ("cases/separator.toml", ["solver.duration=0.3", "output.checkpoint_every=0.02"]),
    "soft": ("cases/soft-separator.toml", ["solver.duration=0.15", "output.checkpoint_every=0.01"]),
}
SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)


def command(case: str, out: Path, sets: list[str]) -> list[str]:
    overrides = [a for s in sets for a in ("--set", s)]
    return [sys.executable, "-m", "perga.cli", "run", case, "-o", str(out), "--quiet", *overrides]


def outputs(run: Path) -> list[str]:
    return sorted(
        str(p.relative_to(run))
        for p in run.rglob("*")
        if p.is_file() and "checkpoints" not in p.parts and p.name != "summary.json"
    )


def identical(run: Path, reference: Path) -> bool:
    files = outputs(reference)
    return outputs(run) == files and all(filecmp.cmp(run / f, reference / f, False) for f in files)


def trial(
    case: str, sets: list[str], reference: Path, out: Path, signum: int, moment: float
) -> str:
    """One stop at ``moment`` s after launch and its resumption: the outcome's name."""
    proc = subprocess.Popen(command(case, out, sets), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)  # fmt: skip
    time.sleep(moment)
    proc.send_signal(signum)
    if proc.wait(timeout=300) == 0:
        return "ended first"
    if not (out / "case.toml").exists():
        return "stopped before the run began"
    summary = out / "summary.json"
    if summary.exists() and json.loads(summary.read_text())["status"] == "completed":
        return "ended first"  # the signal came as the process was exiting
    if signum != signal.SIGKILL:
        assert_readable(out)  # a killed run has no summary.json until it is resumed
    resumed = subprocess.run(
        [sys.executable, "-m", "perga.cli", "run", "--resume", str(out), "--quiet"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    if resumed.returncode == 2 and "has no checkpoint" in resumed.stderr:
        return "no checkpoint yet"
    if resumed.returncode != 0:
        return f"resume failed: {resumed.stderr.strip()[-200:]}"
    assert_readable(out)
    return "identical" if identical(out, reference) else "DIFFERENT"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=20, help="trials per signal and engine")
    parser.add_argument("--seed", type=int, default=15)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    print(f"load average at start: {os.getloadavg()[0]:.2f}; {args.trials} trials each")
    with tempfile.TemporaryDirectory() as scratch:
        root = Path(scratch)
        for engine, (case, sets) in CASES.items():
            reference = root / f"{engine}-reference"
            start = time.perf_counter()
            subprocess.run(command(case, reference, sets), check=True)
            span = time.perf_counter() - start
            for signum in SIGNALS:
                outcomes: Counter[str] = Counter()
                for k in range(args.trials):
                    out = root / f"{engine}-{signum}-{k}"
                    moment = rng.uniform(0.05, span)
                    outcomes[trial(case, sets, reference, out, signum, moment)] += 1
                    shutil.rmtree(out, ignore_errors=True)
                name = signal.Signals(signum).name
                print(f"{engine:5s} {name:7s} (run {span:.1f} s): " + ", ".join(
                    f"{n} {what}" for what, n in sorted(outcomes.items())), flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
