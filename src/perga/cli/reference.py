"""The reference pages generated from the code, in docs/reference/: the command line (cli.md,
from perga's argument parser), the metrics (metrics.md, from their registry and the reasons
their functions give when a run cannot give one) and the case files (case-files.md,
:func:`perga.case.reference.markdown_reference`). ``python -m perga.cli.reference`` rewrites
the three; a test fails when a committed page differs from what this module writes.

argparse has no public way to list a parser's subcommands and arguments: the parser is built
by :func:`perga.cli.build_parser` as an ``ArgumentParser`` that records them as they are added.
"""

from __future__ import annotations

import argparse
import ast
import inspect
import math
import re
import sys
from collections import defaultdict
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from unittest import mock

from perga.case.reference import markdown_reference, rst_to_markdown, table_cell
from perga.cli import build_parser
from perga.stats import metrics

REFERENCE = Path(__file__).resolve().parents[3] / "docs" / "reference"
"""The generated pages' folder in the source tree."""
REGENERATE = "python -m perga.cli.reference"
"""The command that rewrites the generated pages."""
WIDTH = 100
"""Line width of the usage lines (argparse's own follows the terminal)."""
UNKNOWN = "…"
"""What stands for a value known only when a run is read, in a metric's reason."""


def _generated(source: str) -> str:
    return (
        f"Generated from {source}: `{REGENERATE}` rewrites this page and the other generated "
        "pages of docs/reference/ (a test fails when one is out of date)."
    )


def _anchor(heading: str) -> str:
    """The anchor GitHub gives a heading: lower case, punctuation but - and _ dropped, spaces
    as hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")


@dataclass(frozen=True)
class _Command:
    """A command's parser, the arguments added to it in order and its one-line help."""

    parser: argparse.ArgumentParser
    arguments: list[argparse.Action]
    summary: str = ""


def _commands() -> tuple[_Command, dict[str, _Command]]:
    """perga's parser and its subcommands by name, in order, as :func:`perga.cli.build_parser`
    builds them, their arguments recorded as they are added (argparse has no public way to
    list them afterwards)."""
    arguments: dict[int, list[argparse.Action]] = defaultdict(list)
    summaries: dict[str, str] = {}
    subparsers: list[Any] = []
    add_argument = argparse.ArgumentParser.add_argument
    add_subparsers = argparse.ArgumentParser.add_subparsers

    def recording_add_argument(self: argparse.ArgumentParser, *args: Any, **kw: Any) -> Any:
        action = add_argument(self, *args, **kw)
        arguments[id(self)].append(action)
        return action

    def recording_add_subparsers(self: argparse.ArgumentParser, **kw: Any) -> Any:
        action = add_subparsers(self, **kw)
        add_parser = action.add_parser

        def recording_add_parser(name: str, **options: Any) -> argparse.ArgumentParser:
            summaries[name] = options.get("help", "")
            return add_parser(name, **options)

        action.add_parser = recording_add_parser
        arguments[id(self)].append(action)
        subparsers.append(action)
        return action

    add_group = argparse.ArgumentParser.add_mutually_exclusive_group

    def recording_add_group(self: argparse.ArgumentParser, **kw: Any) -> Any:
        group = add_group(self, **kw)
        add_to_group = group.add_argument

        def recording_add_to_group(*args: Any, **options: Any) -> argparse.Action:
            action = add_to_group(*args, **options)
            arguments[id(self)].append(action)
            return action

        group.add_argument = recording_add_to_group
        return group

    with (
        mock.patch.object(argparse.ArgumentParser, "add_argument", recording_add_argument),
        mock.patch.object(argparse.ArgumentParser, "add_subparsers", recording_add_subparsers),
        mock.patch.object(
            argparse.ArgumentParser, "add_mutually_exclusive_group", recording_add_group
        ),
    ):
        parser = build_parser()
    (commands,) = subparsers
    return _Command(parser, arguments[id(parser)]), {
        name: _Command(sub, arguments[id(sub)], summaries[name])
        for name, sub in commands.choices.items()
    }


def _usage(command: _Command) -> str:
    parser = command.parser
    formatter = parser.formatter_class(prog=parser.prog, width=WIDTH)
    formatter.add_usage(parser.usage, command.arguments, [])
    return formatter.format_help().strip()


def _invocation(action: argparse.Action) -> str:
    """How an argument is written, as ``--help`` shows it: ``CASE``, ``--quiet``,
    ``-o OUTPUT, --output OUTPUT``, ``--format {text,json}``."""
    if not action.option_strings:
        return str(action.metavar or action.dest)
    if action.nargs == 0:
        return ", ".join(action.option_strings)
    if action.metavar is not None:
        value = str(action.metavar)
    elif action.choices is not None:
        value = "{" + ",".join(map(str, action.choices)) + "}"
    else:
        value = action.dest.upper()
    return ", ".join(f"{option} {value}" for option in action.option_strings)


def _argument_rows(command: _Command) -> list[str]:
    """One Markdown table row per argument and option (the help option left out)."""
    rows = []
    for action in command.arguments:
        if isinstance(action.help, str) and action.help == argparse.SUPPRESS:
            continue
        if "-h" in action.option_strings:
            continue
        default = action.default
        if action.required:
            default = "required"
        elif default in (None, False, argparse.SUPPRESS) or action.nargs == 0:
            default = ""
        meaning = action.help % {**vars(action), "prog": command.parser.prog} if action.help else ""
        cells = (f"`{_invocation(action)}`", table_cell(str(default)), table_cell(meaning))
        rows.append(f"| {' | '.join(cells)} |")
    return rows


def _command_section(name: str, command: _Command) -> str:
    parser = command.parser
    blocks = [f"## `perga {name}`", command.summary[:1].upper() + command.summary[1:] + "."]
    if parser.description:
        blocks.append(parser.description)
    blocks.append(f"```text\n{_usage(command)}\n```")
    rows = _argument_rows(command)
    if rows:
        blocks.append("\n".join(["| argument | default | meaning |", "|---|---|---|", *rows]))
    if parser.epilog:
        blocks.append(f"```text\n{parser.epilog.strip()}\n```")
    return "\n\n".join(blocks)


def cli_page() -> str:
    """docs/reference/cli.md: every command, its usage, arguments and options with their help
    and defaults, and its examples."""
    perga, commands = _commands()
    index = "\n".join(
        ["| command | what it does |", "|---|---|"]
        + [
            f"| [`perga {name}`](#{_anchor(f'perga {name}')}) | {table_cell(command.summary)} |"
            for name, command in commands.items()
        ]
    )
    blocks = [
        "# Command line",
        _generated("perga's argument parser (`perga.cli`)"),
        f"{perga.parser.description}\n\n`perga --help` and `perga COMMAND --help` print the same.",
        f"```text\n{_usage(perga)}\n\n{perga.parser.epilog.strip()}\n```",
        index,
        *(_command_section(name, command) for name, command in commands.items()),
    ]
    return "\n\n".join(blocks) + "\n"


def _text(node: ast.expr, known: dict[str, object]) -> str:
    """The text of a message: a string, or an f-string with the values known put in and
    :data:`UNKNOWN` for the others."""
    if isinstance(node, ast.Constant):
        return str(node.value)
    if isinstance(node, ast.Name) and node.id in known:
        return str(known[node.id])
    if isinstance(node, ast.FormattedValue) and node.format_spec is None:
        return _text(node.value, known)
    if isinstance(node, ast.JoinedStr):
        return "".join(_text(part, known) for part in node.values)
    return UNKNOWN


def _truth(test: ast.expr, known: dict[str, object]) -> bool | None:
    """Whether ``name == constant`` (or ``!=``) holds for a known name; None if not known."""
    if not (
        isinstance(test, ast.Compare)
        and isinstance(test.left, ast.Name)
        and test.left.id in known
        and len(test.ops) == 1
        and isinstance(test.ops[0], ast.Eq | ast.NotEq)
        and isinstance(test.comparators[0], ast.Constant)
    ):
        return None
    equal = known[test.left.id] == test.comparators[0].value
    return equal if isinstance(test.ops[0], ast.Eq) else not equal


class _Reasons:
    """The messages of the :class:`~perga.stats.metrics.MetricUnavailableError` a function of
    :mod:`perga.stats.metrics` raises, itself or through the module's functions it calls (with
    the constants it hands them, which rule out the branches that compare them)."""

    def __init__(self) -> None:
        tree = ast.parse(inspect.getsource(metrics))
        self.functions = {n.name: n for n in tree.body if isinstance(n, ast.FunctionDef)}

    def of(self, function: Callable[..., float]) -> list[str]:
        found: list[str] = []
        self._function(self.functions[function.__name__], {}, found, ())
        return list(dict.fromkeys(found))

    def _function(
        self, node: ast.FunctionDef, known: dict[str, object], found: list[str], stack: tuple
    ) -> None:
        if node.name not in stack:
            self._block(node.body, known, found, (*stack, node.name))

    def _block(self, body: list[ast.stmt], known: dict, found: list[str], stack: tuple) -> bool:
        """Collect the reasons of ``body``; whether it surely returns."""
        for statement in body:
            if isinstance(statement, ast.If):
                self._expression(statement.test, known, found, stack)
                truth = _truth(statement.test, known)
                taken = [b for b, t in ((statement.body, True), (statement.orelse, False))
                         if truth in (None, t)]  # fmt: skip
                returns = [self._block(b, known, found, stack) for b in taken]
                if truth is not None and returns[0]:
                    return True
                continue
            self._expression(statement, known, found, stack)
            if isinstance(statement, ast.Return):
                return True
        return False

    def _expression(self, node: ast.AST, known: dict, found: list[str], stack: tuple) -> None:
        for sub in ast.walk(node):
            if not isinstance(sub, ast.Call) or not isinstance(sub.func, ast.Name):
                continue
            if sub.func.id == metrics.MetricUnavailableError.__name__:
                found.append(_text(sub.args[0], known))
            elif sub.func.id in self.functions:
                callee = self.functions[sub.func.id]
                self._function(callee, self._arguments(callee, sub, known), found, stack)

    @staticmethod
    def _arguments(callee: ast.FunctionDef, call: ast.Call, known: dict) -> dict[str, object]:
        """The callee's parameters whose values are constants: its defaults, then the call's."""
        names = [a.arg for a in callee.args.args]
        values: dict[str, object] = {
            name: d.value
            for name, d in zip(names[::-1], callee.args.defaults[::-1], strict=False)
            if isinstance(d, ast.Constant)
        }
        for name, arg in zip(names, call.args, strict=False):
            if isinstance(arg, ast.Constant):
                values[name] = arg.value
            elif isinstance(arg, ast.Name) and arg.id in known:
                values[name] = known[arg.id]
            else:
                values.pop(name, None)
        return values


def _bound(value: float) -> str:
    return "∞" if math.isinf(value) else f"{value:.6g}".replace("-", "−")


def _metric_name(metric: metrics.Metric) -> str:
    """How a metric is asked for: ``NAME``, or ``NAME:ARG`` for one that takes an argument."""
    return f"{metric.name}:ARG" if metric.argument else metric.name


def _metric_section(metric: metrics.Metric, reasons: list[str]) -> str:
    name = _metric_name(metric)
    facts = [f"- unit: {metric.unit}"]
    if metric.argument:
        facts.append(f"- ARG: {metric.argument}")
    if metric.bounds:
        lo, hi = metric.bounds
        closing = ")" if math.isinf(hi) else "]"
        facts.append(f"- range: [{_bound(lo)}, {_bound(hi)}{closing}: {metric.convention}")
    facts.append(
        "- unavailable (the reason `perga metrics RUN` prints), where:\n"
        + "\n".join(f"  - {reason}" for reason in reasons)
    )
    doc = rst_to_markdown(inspect.cleandoc(metric.compute.__doc__ or ""))
    return "\n\n".join([f"## `{name}`", doc, "\n".join(facts)])


def metrics_page() -> str:
    """docs/reference/metrics.md: every named metric with its unit, its argument, its range and
    what it means, and the reasons a run may not give it."""
    reasons = _Reasons()
    index = "\n".join(
        ["| metric | unit | meaning |", "|---|---|---|"]
        + [f"| [`{_metric_name(m)}`](#{_anchor(_metric_name(m))}) | {m.unit} | "
           f"{table_cell(m.description)} |"
           for m in metrics.METRICS.values()]
    )  # fmt: skip
    renamed = "\n".join(f"- `{old}`: now {new}" for old, new in metrics.RENAMED.items())
    blocks = [
        "# Metrics",
        _generated("`perga.stats.metrics`"),
        "`perga metrics` lists them; `perga metrics RUN [NAME...]` computes them for a run (a "
        "metric it cannot give is printed as unavailable, with the reason); `perga sweep "
        "--metric NAME` and `perga calibrate` (a column of the measured data) take them by "
        "name. Units are SI; `-` is a dimensionless number.",
        rst_to_markdown(inspect.cleandoc(metrics.__doc__ or "")),
        index,
        *(_metric_section(m, reasons.of(m.compute)) for m in metrics.METRICS.values()),
        "## Renamed\n\nAsked for by an old name, a metric is refused naming its successors:\n\n"
        + renamed,
    ]
    return "\n\n".join(blocks) + "\n"


def pages() -> dict[str, str]:
    """Every generated page of docs/reference/ by file name, as the code writes it now."""
    return {
        "case-files.md": markdown_reference(),
        "cli.md": cli_page(),
        "metrics.md": metrics_page(),
    }


def main(argv: Sequence[str] | None = None) -> int:
    """Write the generated pages into a folder (default: the source tree's docs/reference/)."""
    parser = argparse.ArgumentParser(prog=REGENERATE, description="Write the generated pages.")
    parser.add_argument("folder", nargs="?", type=Path, default=REFERENCE)
    folder = parser.parse_args(argv).folder
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in pages().items():
        (folder / name).write_text(text, encoding="utf-8")
        print(folder / name)
    return 0


if __name__ == "__main__":
    sys.exit(main())
