"""Command-line options shared by the studies."""

import pytest

from perga.cli import build_parser


@pytest.mark.parametrize("command", ["sweep", "window"])
def test_workers_at_least_one(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    """--workers 1 is taken; 0 and a non-number are refused with exit 2, naming the option
    (a sweep used to take 0 silently as "all free cores")."""
    parser = build_parser()
    base = [command, "cases/rebound-test.toml", "--set", "rotor.rpm=500:600:2", "-o", "out"]
    assert parser.parse_args([*base, "--workers", "1"]).workers == 1
    for bad in ("0", "two"):
        with pytest.raises(SystemExit) as stop:
            parser.parse_args([*base, "--workers", bad])
        assert stop.value.code == 2
        assert "--workers" in capsys.readouterr().err


def test_the_help_examples_parse():
    """Every command line in ``perga --help``'s examples is one the parser takes."""
    import shlex

    from perga.cli import EXAMPLES, build_parser

    lines = [x.strip() for x in EXAMPLES.splitlines() if x.strip().startswith("perga ")]
    assert len(lines) >= 7
    for line in lines:
        command = shlex.split(line.split("   ")[0])
        build_parser().parse_args(command[1:])
