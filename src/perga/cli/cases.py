"""Case files: ``perga validate``, ``perga new`` (a commented template), ``perga schema``."""

from __future__ import annotations

import argparse
from pathlib import Path

from perga.cli.common import AddParser, problems, warn


def validate(args: argparse.Namespace) -> int:
    """Every problem of each case, or "ok"."""
    from perga.case import CaseError
    from perga.model.compile import validated

    failed = 0
    for path in args.cases:
        try:
            case = validated(path)
        except CaseError as exc:
            failed += 1
            problems(exc.problems)
        else:
            print(f"ok: {path}")
            warn(path, case)
    return 2 if failed else 0


def new(args: argparse.Namespace) -> int:
    """Write a template and check that it loads."""
    from perga.case import CaseError
    from perga.case.templates import TEMPLATES, write_template
    from perga.model.compile import load_system

    if args.template not in TEMPLATES:
        names = ", ".join(f"{k} ({v[1]})" for k, v in TEMPLATES.items())
        return problems([f"perga new: no template {args.template!r}; there are: {names}"])
    try:
        written = write_template(args.template, args.output, args.overwrite)
    except FileExistsError as exc:
        return problems([str(exc)])
    except OSError as exc:
        return problems([f"cannot write {args.output}: {exc.strerror or exc}"])
    try:
        load_system(args.output)
    except CaseError as exc:  # a template that does not load is perga's defect
        problems(exc.problems)
        return 1
    print(f"wrote {', '.join(str(p) for p in written)}; next: perga run {args.output}")
    return 0


def schema(args: argparse.Namespace) -> int:
    """The JSON Schema, or the Markdown reference."""
    from perga.case.reference import json_schema, markdown_reference

    print(
        markdown_reference() if args.markdown else json_schema(), end="" if args.markdown else "\n"
    )
    return 0


def add_parsers(add: AddParser) -> None:
    """``perga new``, ``validate`` and ``schema``."""
    parser = add(
        "new",
        help="start a case from a commented template",
        description="Write a commented case to start from (a bundled case, its geometry files "
        "copied beside it). Templates: single-impact, rebound, separator, soft-separator, "
        "fed-separator.",
        epilog="example: perga new fed-separator -o my.toml && perga run my.toml",
    )
    parser.add_argument("template", nargs="?", default="separator", help="default: separator")
    parser.add_argument("-o", "--output", type=Path, required=True, help="the case file to write")
    parser.add_argument("--overwrite", action="store_true", help="replace files in the way")
    parser.set_defaults(handler=new)
    parser = add("validate", help="check case files: schema and physical cross-checks")
    parser.add_argument("cases", nargs="+", type=Path, metavar="CASE")
    parser.set_defaults(handler=validate)
    parser = add("schema", help="print the case-file JSON Schema")
    parser.add_argument(
        "--markdown",
        action="store_true",
        help="the Markdown reference, docs/reference/case-files.md",
    )
    parser.set_defaults(handler=schema)
