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
