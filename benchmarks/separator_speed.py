"""Wall seconds per simulated second of whole separator runs (issue 14), and the share of the
step spent outside the soft kernel, optionally side by side with another commit.

Each measurement is one `perga run` done in a fresh subprocess (``--one``) through
``perga.run.run_case``, with ``Simulation.advance`` (``Simulation.step`` in a tree before
it), ``SoftGranules.step`` (a kernel call from Python) and the soft model's compiled whole
steps (``perga.contact.soft.machine_steps``) wrapped by timers: wall time of the run
(``summary.json``, build and output included), time in the steps, time in the kernel (in the
compiled steps, their time times the kernel's share of the processor cycles they counted), and
the share of the granule steps that coasted (``perga.contact.soft.coasting``). Variants (this tree,
and with ``--against REF`` the commit REF checked out in a temporary worktree) are interleaved
run by run; figures are medians over ``--repeats``, ratios are medians of run-by-run paired ratios.
Every variant first runs each case once untimed (numba's cache).

    python benchmarks/separator_speed.py                       # the three cases, this tree
    python benchmarks/separator_speed.py --against d605bbb     # side by side with a commit
    python benchmarks/separator_speed.py --cases soft-separator --repeats 5
    python benchmarks/separator_speed.py --cases soft-separator-1000 --seconds 0.05
    python benchmarks/separator_speed.py --cases soft-separator-1000 --seconds 0.05 \
        --setting contact_model.steps_per_contact=20      # this tree at a longer step as well

``--setting KEY=VALUE`` (repeatable) adds this tree with that case override as one more
variant, interleaved with the others: what a setting, such as a longer step, gains in time.
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

from call_timer import timed
from trees import worktree

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "soft-separator": (ROOT / "cases/soft-separator.toml", 0.5),
    "separator": (ROOT / "cases/separator.toml", 0.5),
    "soft-separator-1000": (ROOT / "benchmarks/cases/soft-separator-1000.toml", 0.01),
}
"""Name -> (case file, simulated seconds measured)."""


def one(case: str, duration: float, out: str, overrides: list[str]) -> None:
    """Run ``case`` for ``duration`` s into ``out``, with the case ``overrides``, the steps and
    the kernel timed; print JSON."""
    import perga.contact.soft.model as soft
    from perga.case import load_case
    from perga.contact.soft.granules import SoftGranules
    from perga.engine.simulation import Simulation

    try:
        from perga.run import prepare_directory, run_case
    except ImportError:  # a tree before perga.run
        from perga.runner import prepare_directory, run_case

    timers = {"step": 0.0, "kernel": 0.0, "coasted": 0, "granule_steps": 0}

    stepping = "advance" if hasattr(Simulation, "advance") else "step"  # advance since 2026-11-27
    setattr(Simulation, stepping, timed(timers, "step", getattr(Simulation, stepping)))
    kernel_step = timed(timers, "kernel", SoftGranules.step)

    def counted(self, n_steps=1, **kwargs):
        """A kernel call from Python, timed, with its granule steps and those that coasted."""
        before = self.coasted
        kernel_step(self, n_steps, **kwargs)
        timers["coasted"] += self.coasted - before
        timers["granule_steps"] += self.n * n_steps

    SoftGranules.step = counted  # type: ignore[method-assign]
    if hasattr(soft, "machine_steps"):
        compiled = soft.machine_steps

        def shared(*args):
            """Whole steps in one compiled call: the kernel's time is the call's time times the
            kernel's share of the cycles it counted; the granule steps as above."""
            start = time.perf_counter()
            out = compiled(*args)
            timers["kernel"] += (time.perf_counter() - start) * out[10] / max(out[11], 1)
            settings, granules = args[5][0], args[5][1]
            timers["coasted"] += out[3]
            timers["granule_steps"] += out[0] * settings[0] * granules[0].shape[0]
            return out

        soft.machine_steps = shared
    path = Path(case)
    loaded = load_case(
        path, overrides=[f"solver.duration={duration}", "solver.threads=1", *overrides]
    )
    prepare_directory(Path(out), overwrite=True)
    summary = run_case(loaded, path, Path(out))
    print(
        json.dumps(
            {
                "status": summary.status,
                "wall": summary.wall_time,
                "simulated": summary.simulated_time,
                "step": timers["step"],
                "kernel": timers["kernel"],
                "coasted": timers["coasted"] / max(timers["granule_steps"], 1),
                "threads": summary.threads,
            }
        )
    )


def measure(
    source: Path, case: Path, duration: float, overrides: tuple[str, ...] = ()
) -> dict[str, float]:
    """One run in a subprocess with ``source`` (a src/ folder) first on the path and the case
    ``overrides``."""
    env = dict(os.environ, PYTHONPATH=str(source), NUMBA_NUM_THREADS="1")
    with tempfile.TemporaryDirectory() as out:
        done = subprocess.run(
            [sys.executable, __file__, "--one", str(case), str(duration), out, *overrides],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    if result["status"] != "completed":
        raise RuntimeError(f"{case} with {source}: {result['status']}")
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", choices=sorted(CASES), default=list(CASES))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seconds", type=float, help="simulated seconds of every case")
    parser.add_argument("--against", help="a git ref to measure side by side")
    parser.add_argument(
        "--setting", action="append", default=[], metavar="KEY=VALUE",
        help="also this tree with this case override (repeatable: one variant each)",
    )  # fmt: skip
    parser.add_argument("--one", nargs="+", metavar="CASE S OUT KEY=VALUE", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        one(args.one[0], float(args.one[1]), args.one[2], args.one[3:])
        return
    variants: dict[str, tuple[Path, tuple[str, ...]]] = {"this tree": (ROOT / "src", ())}
    for setting in args.setting:
        variants[setting] = (ROOT / "src", (setting,))
    if args.against:
        variants[args.against] = (worktree(args.against), ())
    print(f"load average at start: {os.getloadavg()[0]:.2f}; cores: {os.cpu_count()}")
    for name in args.cases:
        case, duration = CASES[name]
        duration = args.seconds or duration
        for source, overrides in variants.values():
            measure(source, case, min(duration, 0.002), overrides)  # warm numba's cache
        runs: dict[str, list[dict[str, float]]] = {v: [] for v in variants}
        for _ in range(args.repeats):
            for variant, (source, overrides) in variants.items():
                runs[variant].append(measure(source, case, duration, overrides))
        print(f"\n{name}: {duration} s simulated, {args.repeats} runs per variant, 1 thread")
        header = ("variant", "wall s/s", "step s/s", "kernel s/s", "outside kernel", "coasted")
        width = max(12, *map(len, variants))
        print(f"{{:>{width}}} {{:>9}} {{:>9}} {{:>10}} {{:>15}} {{:>8}}".format(*header))
        for variant, results in runs.items():
            wall = statistics.median(r["wall"] / r["simulated"] for r in results)
            step = statistics.median(r["step"] / r["simulated"] for r in results)
            kernel = statistics.median(r["kernel"] / r["simulated"] for r in results)
            outside = statistics.median(1 - r["kernel"] / r["step"] for r in results)
            share = f"{100 * outside:.0f} %" if kernel > 0 else "-"
            coasted = statistics.median(r.get("coasted", 0.0) for r in results)
            print(
                f"{variant:>{width}} {wall:9.1f} {step:9.1f} {kernel:10.1f} {share:>15} "
                f"{100 * coasted:7.0f} %"
            )
        for variant in list(runs)[1:]:
            pairs = zip(runs["this tree"], runs[variant], strict=True)
            ratios = [a["wall"] / b["wall"] for a, b in pairs]
            print(f"wall ratio this tree / {variant}: median {statistics.median(ratios):.3f} "
                  f"(runs {min(ratios):.3f}-{max(ratios):.3f})")  # fmt: skip
    print(f"\nload average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
