"""The ``perga`` command line: parses, calls the library, prints.

Exit codes: 0 success, 2 bad input (the problems are printed, never a traceback), 1 a failed run,
3 a run that reached its end with its energy ledger off (beyond ``solver.ledger_tolerance``),
128 + the signal's number after a stop signal (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP;
:mod:`perga.stopping`). Everything heavy is imported inside the commands, after the stop signals
are handled, so a signal during start-up is a clean stop too.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from perga import __version__
from perga.cli import cases, paper, run, studies, views
from perga.cli.common import problems
from perga.stopping import StopRequest, StopSignal, exit_status, raise_on_stop_signals

EXAMPLES = """examples:
  perga new fed-separator -o my.toml          a commented case to start from
  perga validate my.toml                      every problem of a case, with the allowed range
  perga run my.toml --set rotor.rpm=1500      simulate (any key overridden) into runs/my
  perga report runs/my                        report.md with figures of the run
  perga run --resume runs/my                  go on after a stop or a crash
  perga sweep my.toml --set rotor.rpm=500:1700:4 --metric released_fraction -o sweep
  perga window my.toml --set rotor.rpm=500:1700:4 --set hammers.mass=0.025:0.075:3 -o window

exit status: 0 done, 1 a run that failed, 2 bad input, 3 a run whose energy ledger is off,
128 + N after signal N. Every case key: docs/reference/case-files.md (perga schema --markdown)."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand (each command group's module adds its own)."""
    parser = argparse.ArgumentParser(
        prog="perga",
        description="perga: bee-bread granules struck by hammers on a rotor (2-D DEM), checked "
        "against the analytical model. Every run is driven by a case file (TOML).",
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"perga {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    run.add_parser(sub.add_parser)
    views.add_parsers(sub.add_parser)
    paper.add_parsers(sub.add_parser)
    studies.add_parsers(sub.add_parser)
    cases.add_parsers(sub.add_parser)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``perga`` console script."""
    raise_on_stop_signals()
    try:
        with StopRequest() as stop:  # imports are never interrupted halfway (perga.stopping)
            from perga.case import CaseError

            args = build_parser().parse_args(argv)
            stop.check()
        try:
            return args.handler(args)
        except CaseError as exc:
            return problems(exc.problems)
    except KeyboardInterrupt as exc:  # a stop signal (perga.stopping) outside a run's own report
        name = exc.name if isinstance(exc, StopSignal) else "SIGINT"
        print(f"stopped by {name}", file=sys.stderr)
        return exit_status(exc)
