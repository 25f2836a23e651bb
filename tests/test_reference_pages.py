"""The generated reference pages of docs/reference/: each committed page is what its generator
writes now (``python -m perga.cli.reference`` rewrites them), and each generator leaves out
nothing: every command and option of ``perga --help``, every reason a metric gives when a
run cannot give it, every table of a case file once."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from perga.case import load_case
from perga.cli import main
from perga.cli.reference import UNKNOWN, pages
from perga.cli.reference import main as write_pages
from perga.run import prepare_directory, run_case
from perga.stats import load_run
from perga.stats.metrics import METRICS, MetricUnavailableError, evaluate

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "docs" / "reference"
PAGES = pages()


@pytest.mark.parametrize("name", sorted(PAGES))
def test_each_generated_page_is_current(name: str) -> None:
    """Regenerate with `python -m perga.cli.reference` when this fails."""
    assert (REFERENCE / name).read_text(encoding="utf-8") == PAGES[name], (
        f"docs/reference/{name} is out of date: python -m perga.cli.reference"
    )


def test_the_module_writes_every_page(tmp_path: Path) -> None:
    assert write_pages([str(tmp_path)]) == 0
    assert {p.name: p.read_text(encoding="utf-8") for p in tmp_path.iterdir()} == PAGES


def _sections(page: str) -> dict[str, str]:
    """A page's ``## `NAME` `` sections by NAME."""
    return {part.split("`")[1]: part for part in page.split("\n## ")[1:] if part.startswith("`")}


def _help(args: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit):
        main([*args, "--help"])
    return capsys.readouterr().out


def test_the_cli_page_has_every_command_and_option(capsys: pytest.CaptureFixture[str]) -> None:
    """Every command ``perga --help`` lists has a section holding every option and argument
    its own ``--help`` shows."""
    usage = _help([], capsys)
    commands = re.search(r"\{([\w,-]+)\}", usage)[1].split(",")
    sections = _sections(PAGES["cli.md"])
    assert sorted(sections) == sorted(f"perga {c}" for c in commands)
    for command in commands:
        text = _help([command], capsys)
        options = set(re.findall(r"(?<![\w-])--?[a-zA-Z][\w-]*", text)) - {"-h", "--help"}
        positionals = re.findall(r"^  ([A-Z_]+)$", text, re.MULTILINE)
        table = sections[f"perga {command}"].partition("| argument |")[2]
        for name in (*options, *positionals):
            token = rf"(?<![\w-]){re.escape(name)}(?![\w-])"
            assert re.search(token, table), f"perga {command}: {name} is not in its table"


def _shot(tmp_path: Path, name: str, *overrides: str):
    """The rebound test's shot run with ``overrides`` (3 ms), loaded."""
    case_path = ROOT / "cases" / "rebound-test.toml"
    directory = tmp_path / name
    prepare_directory(directory, overwrite=True)
    run_case(load_case(case_path, overrides=list(overrides)), case_path, directory)
    return load_run(directory)


SHOTS = {
    "head-on": ("granules.placement.angle=0.0",),
    "granules-only": ('output.record=["granules"]',),
}
"""Shots whose metrics fail for many reasons: a head-on shot (no tangential motion, one
impact, no comb, no outlet, no damage), and one that recorded only its granules."""


@pytest.mark.parametrize("shot", ["head-on", "granules-only"])
def test_the_metrics_page_names_every_reason_a_run_gives(tmp_path: Path, shot: str) -> None:
    """Every metric, asked of the shot, either is given or fails with a reason that its
    section lists (…, a value known only from the run, matches one word); every metric has a
    section with its unit."""
    sections = _sections(PAGES["metrics.md"])
    run = _shot(tmp_path, shot, *SHOTS[shot])
    reasons = 0
    for metric in METRICS.values():
        name = f"{metric.name}:ARG" if metric.argument else metric.name
        section = sections[name]
        assert f"- unit: {metric.unit}\n" in section
        listed = re.findall(r"^  - (.+)$", section, re.MULTILINE)
        patterns = [re.escape(r).replace(re.escape(UNKNOWN), r"\S+") for r in listed]
        asked = {"n, the impact number (1, 2, ...)": ":2", "t, s": ":1.0"}.get(metric.argument, "")
        try:
            evaluate(run, metric.name + asked)
        except MetricUnavailableError as exc:
            reasons += 1
            assert any(re.fullmatch(p, str(exc)) for p in patterns), (name, str(exc))
    assert reasons >= 8  # the shot exercises the reasons, not only the values


def test_the_case_file_page_has_each_table_once_in_markdown() -> None:
    """One heading per table (a table of several forms: one per kind), no reStructuredText
    left outside the TOML examples, every table cell escaped."""
    page = PAGES["case-files.md"]
    headings = re.findall(r"^## .+$", page, re.MULTILINE)
    assert len(headings) == len(set(headings))
    assert '## `[granules.placement]` with `kind = "shot"`' in headings
    assert "## `[[contacts]]`" in headings
    prose = re.sub(r"^```toml\n.*?^```$", "", page, flags=re.MULTILINE | re.DOTALL)
    assert "``" not in prose and not re.search(r":\w+:`", prose)
    assert "\\|α\\| <= swing_limit" in page
