"""The fuzz counts. Mutants of the bundled cases, byte strings that are no case file, and
bundled cases pointed at broken copies of their geometry files, drawn by the strategies of
``tests/case/test_fuzz.py`` (seeded): how many were refused with their problems (exit 2 in the
CLI), loaded and built, loaded as parameter sets, and how many did anything else (a traceback:
any count there is a defect) or took longer than 10 s. Then mutants over every section of the
schema and sets of ``--set`` overrides, each validated and, if accepted, run for a few steps in
a worker process with a timeout (``tests/case/fuzz_worker.py``): mutants, refused, accepted
(parameter sets), run, tracebacks and hangs.

    python benchmarks/fuzz_counts.py    # 1,000 + 200 + 300 loaded; 2,000 + 1,000 run
    python benchmarks/fuzz_counts.py --cases 3000 --every-section 4000 --sets 2000 --seed 7
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.case.test_fuzz

from tests.case.test_fuzz import ROOT, SECONDS, broken_geometry, fuzz, mutants

from perga.case import CaseError, load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case


def outcome(path: Path, counts: Counter, slowest: list[float]) -> None:
    """Load (and build) the case at ``path``; count how it ended."""
    start = time.monotonic()
    try:
        case = load_case(path)
        if case.chamber is None:
            counts["loaded as a parameter set"] += 1
        else:
            Simulation(compile_case(case))
            counts["loaded and built"] += 1
    except CaseError as exc:
        named = all(p.startswith(f"{path}: ") for p in exc.problems) and exc.problems
        counts["refused, the file named" if named else "refused, the FILE NOT NAMED"] += 1
    except Exception as exc:  # the count of defects
        counts[f"FAILED: {type(exc).__name__}"] += 1
    took = time.monotonic() - start
    slowest[0] = max(slowest[0], took)
    if took > SECONDS:
        counts[f"SLOWER THAN {SECONDS:g} s"] += 1


def draw(strategy: st.SearchStrategy, n: int, seed_value: int, check) -> None:
    """Run ``check`` on ``n`` examples of ``strategy`` (seeded, no example database)."""

    @seed(seed_value)
    @settings(max_examples=n, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(example=strategy)
    def run(example) -> None:
        check(example)

    run()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=1000, help="mutated case files")
    parser.add_argument("--bytes", type=int, default=200, help="random byte strings")
    parser.add_argument("--geometry", type=int, default=300, help="broken geometry files")
    parser.add_argument(
        "--every-section", type=int, default=2000, help="mutants over every section, run"
    )
    parser.add_argument("--sets", type=int, default=1000, help="sets of --set overrides, run")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)

        def case_file(mutant: tuple[str, str]) -> None:
            name, text = mutant
            path = folder / name
            path.write_text(text, encoding="utf-8")
            outcome(path, counts, slowest)

        def garbage(data: bytes) -> None:
            path = folder / "garbage.toml"
            path.write_bytes(data)
            outcome(path, counts, slowest)

        def geometry(broken: tuple[str, str, bytes]) -> None:
            case, relative, data = broken
            target = folder / Path(relative).name
            target.write_bytes(data)
            text = (ROOT / "cases" / case).read_text().replace(f'"{relative}"', f'"{target}"')
            path = folder / case
            path.write_text(text)
            outcome(path, counts, slowest)

        kinds = [
            ("mutated case files", mutants(), args.cases, case_file),
            ("byte strings", st.binary(max_size=2000), args.bytes, garbage),
            ("broken geometry files", broken_geometry(), args.geometry, geometry),
        ]
        for title, strategy, n, check in kinds:
            counts: Counter = Counter()
            slowest = [0.0]
            draw(strategy, n, args.seed, check)
            total = sum(v for k, v in counts.items() if not k.startswith("SLOWER"))
            shown = ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
            print(f"{title}: {total} drawn (seed {args.seed}): {shown}; slowest {slowest[0]:.2f} s",
                  flush=True)  # fmt: skip
        start = time.monotonic()
        found, failures, largest = fuzz(folder, args.every_section, args.sets, args.seed)
        print(
            f"validated and run (seed {args.seed}): mutants {found['mutants']}, --set sets "
            f"{found['override sets']}; refused {found['refused']}, accepted "
            f"{found['accepted'] + found['ran']} (parameter sets, nothing to run: "
            f"{found['accepted']}), run {found['ran']}, tracebacks {found['traceback']}, hangs "
            f"{found['hang']}; {time.monotonic() - start:.0f} s"
        )
        for failure in failures:
            print(f"  {failure[:400]}")
        print(f"the worker's peak memory: {found['peak MB']} MB, reached with {largest[:300]}")


if __name__ == "__main__":
    main()
