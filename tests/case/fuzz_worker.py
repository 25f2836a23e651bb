"""A case file (and ``--set`` overrides) validated, and if accepted run for a few steps, in a
worker process that the fuzz tests (tests/case/test_fuzz.py) and benchmarks/fuzz_counts.py
drive with a timeout: a job that outlasts it is a hang, any exception but the refusal of bad
input (CaseError, exit 2) is a traceback.

The worker (``python -m tests.case.fuzz_worker``) reads one job per line on stdin, JSON
``{"case": PATH, "sets": [KEY=VALUE, ...], "run": DIRECTORY}``, and answers one line per job:
``{"outcome": "refused" | "accepted" | "ran" | "traceback", "detail": ..., "peak_mb": ...}``
(the worker's peak memory so far); the run's own output goes to /dev/null. ``perga run`` is
called as the command line does (:func:`perga.cli.main`), with ``solver.duration`` cut to
``STEPS`` machine steps.
"""

from __future__ import annotations

import json
import os
import resource
import select
import subprocess
import sys
import traceback
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
STEPS = 3
"""Machine steps an accepted mutant is run for (at least the schema's shortest duration)."""
SHORTEST = 1e-6
"""solver.duration's lower bound, s."""
TIMEOUT = 60.0
"""Longest a job may take, s: validation (about 1 s for the slowest bundled case), the start of
a run (imports and compilation are paid once per worker) and its few steps."""
RUN_EXITS = {0, 1, 2, 3}
"""``perga run``'s exit statuses that are answers (done, a failed run with its reason, bad
input, ledger off); anything else, or an exception, is a defect."""


def job(case: str, sets: list[str], run: str) -> dict[str, Any]:
    """Validate ``case`` with ``sets`` as ``perga validate`` does; if accepted, run it for a few
    steps as ``perga run`` does."""
    from perga.case import CaseError
    from perga.cli import main
    from perga.model.compile import validated
    from perga.model.plan import step_plan

    try:
        loaded = validated(case, overrides=sets)
    except CaseError as exc:
        return {"outcome": "refused", "detail": exc.problems[0][:300]}
    if loaded.chamber is None:
        return {"outcome": "accepted", "detail": "a parameter set (nothing to run)"}
    duration = max(SHORTEST, STEPS * step_plan(loaded).machine)
    argv = ["run", case, "-o", run, "--overwrite", "--quiet"]
    argv += [a for s in [*sets, f"solver.duration={duration!r}"] for a in ("--set", s)]
    status = main(argv)
    if status not in RUN_EXITS:
        return {"outcome": "traceback", "detail": f"perga run exit {status}"}
    return {"outcome": "ran", "detail": f"exit {status}"}


def serve() -> None:
    """Answer jobs from stdin until it closes; the runs' own output goes to /dev/null."""
    answers = os.fdopen(os.dup(1), "w")
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    os.dup2(null, 2)
    for line in sys.stdin:
        request = json.loads(line)
        try:
            answer = job(request["case"], request["sets"], request["run"])
        except BaseException as exc:  # every exception is what the fuzz counts
            last = " | ".join(
                line.strip()[:200] for line in traceback.format_exc().splitlines()[-3:]
            )
            answer = {"outcome": "traceback", "detail": f"{type(exc).__name__}: {last}"}
        answer["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss // 1024
        answers.write(json.dumps(answer) + "\n")
        answers.flush()


class Worker:
    """A worker process (``serve``) and a job's answer within ``TIMEOUT`` seconds: a job that
    takes longer is a hang, and the worker is killed and started again."""

    def __init__(self, timeout: float = TIMEOUT) -> None:
        self.timeout = timeout
        self.process: subprocess.Popen[str] | None = None

    def __enter__(self) -> Worker:
        return self

    def __exit__(self, *_: object) -> None:
        self.stop()

    def start(self) -> subprocess.Popen[str]:
        """The worker, started if it is not running."""
        if self.process is None or self.process.poll() is not None:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "tests.case.fuzz_worker"],
                cwd=ROOT,
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                text=True,
            )
        return self.process

    def stop(self) -> None:
        """End the worker (killed if it does not end when its input closes)."""
        if self.process is not None:
            assert self.process.stdin is not None
            self.process.stdin.close()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
            self.process = None

    def __call__(self, case: Path, sets: list[str], run: Path) -> dict[str, Any]:
        """The outcome of one job: the worker's answer, or "hang" after the timeout (the worker
        killed) or "traceback" if it died."""
        process = self.start()
        assert process.stdin is not None and process.stdout is not None
        process.stdin.write(json.dumps({"case": str(case), "sets": sets, "run": str(run)}) + "\n")
        process.stdin.flush()
        ready, _, _ = select.select([process.stdout], [], [], self.timeout)
        if not ready:
            process.kill()
            process.wait()
            self.process = None
            return {"outcome": "hang", "detail": f"no answer within {self.timeout:g} s"}
        line = process.stdout.readline()
        if not line:
            status = process.wait()
            self.process = None
            return {"outcome": "traceback", "detail": f"the worker died (exit {status})"}
        return json.loads(line)


if __name__ == "__main__":
    serve()
