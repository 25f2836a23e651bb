"""``perga run``: a case into a run directory, ``--resume`` a stopped run, ``--from`` another
run's granules (:mod:`perga.run.request`)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from perga.cli.common import AddParser, problems, warn
from perga.progress import progress_bar
from perga.stopping import StopRequest, exit_status


def run(args: argparse.Namespace) -> int:
    """Prepare the request, run it under a progress bar, print the outcome."""
    with StopRequest() as stop:  # the imports and the case, never stopped halfway
        from perga.run.guards import RunStoppedError
        from perga.run.request import BadRequestError, Request, execute, load, outcome, prepare

        request = Request(args.case, args.resume, args.output, args.overwrite,
                          tuple(args.set or ()), args.start_from)  # fmt: skip
        try:
            case, system = load(request)
            warn(args.case or args.resume, case)
            stop.check()
            prepared = prepare(request, case, system)
        except BadRequestError as exc:
            return problems([str(exc)])
    directory = prepared.directory
    bar = progress_bar(
        case.solver.duration,
        "s simulated",
        "perga run",
        args.quiet,
        bar_format="{l_bar}{bar}| {n:.4f}/{total:.4f} s simulated [{elapsed}<{remaining}{postfix}]",
    )
    started = time.perf_counter()

    def progress(t: float, _duration: float, steps: int) -> None:
        bar.update(min(t, bar.total) - bar.n)
        bar.set_postfix_str(f"{steps / max(time.perf_counter() - started, 1e-9):.0f} steps/s")

    try:
        summary = execute(prepared, progress)
    except BadRequestError as exc:
        bar.close()
        return problems([str(exc)])
    except KeyboardInterrupt as exc:
        bar.close()
        print(f"interrupted: everything up to now is in {directory}; perga run --resume "
              f"{directory} goes on from its last checkpoint", file=sys.stderr)  # fmt: skip
        return exit_status(exc)
    except RunStoppedError as exc:
        bar.close()
        print(f"error: the run stopped: {exc}\nwhat was written is in {directory}", file=sys.stderr)
        return 1
    except OSError as exc:  # a full disk, a file system gone read-only, a removed directory
        bar.close()
        print(f"error: the run could not write its output: {exc}\nwhat was written is in "
              f"{directory} (summary.json says where it stopped)", file=sys.stderr)  # fmt: skip
        return 1
    bar.close()
    out, err, status = outcome(summary, directory)
    print("\n".join(out))
    for line in err:
        print(line, file=sys.stderr)
    return status


def add_parser(add: AddParser) -> None:
    """``perga run``'s arguments."""
    parser = add("run", help="simulate a case: tables and summary.json in a run directory")
    parser.add_argument("case", type=Path, metavar="CASE", nargs="?")
    parser.add_argument(
        "--resume",
        type=Path,
        metavar="RUN",
        help="go on with the stopped or killed run RUN from its newest checkpoint (no CASE)",
    )
    parser.add_argument(
        "-o", "--output", type=Path, help="run directory (default: output.directory)"
    )
    parser.add_argument(
        "--from",
        dest="start_from",
        metavar="RUN[:TIME]",
        help="start CASE's granules where the run RUN had them at its last frame at or before "
        "TIME s (default: its last): positions, velocities, spins; RUN's sizes must be CASE's",
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace an existing run directory"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a key of the case, e.g. rotor.rpm=2400 or "
        "contacts.granule-hammer.restitution=0.65 (repeat for several; checked like the file)",
    )
    parser.set_defaults(handler=run)
