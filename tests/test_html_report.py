"""report.html beside every Markdown report: one self-contained page (every figure a data URI,
the tables HTML tables), from the module that writes both and from each report command."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from perga.cli import main
from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.studies.accuracy import Row, StudyResult
from perga.studies.accuracy_report import write_outputs
from perga.studies.window import (
    WindowResult,
    aggregate,
    best_point,
    foundations,
    trade_offs,
    trends,
    window_study,
)
from perga.studies.window_adaptive import run_adaptive
from perga.studies.window_adaptive_report import write_adaptive
from perga.studies.window_odds import assumed_values, read_posterior, run_odds
from perga.studies.window_odds_report import write_odds_map, write_odds_report
from perga.studies.window_report import write_maps, write_report, write_trade_offs
from tests.html_pages import assert_self_contained, figures_of
from tests.studies import test_window_adaptive as adaptive
from tests.studies import test_window_odds as odds

ROOT = Path(__file__).resolve().parents[1]


def _png(path: Path) -> None:
    fig, ax = new_figure((2, 2))
    ax.plot([0, 1], [1, 0])
    save(fig, path)


def test_a_report_becomes_one_page_with_its_figures_and_tables(tmp_path: Path) -> None:
    """A figure beside the report and one in a folder below it (a name markdown-it
    percent-encodes), a table with an aligned column, and text that looks like HTML (shown as
    text, not taken as markup)."""
    (tmp_path / "figures").mkdir()
    _png(tmp_path / "a.png")
    _png(tmp_path / "figures" / "größe.png")
    markdown = "\n".join([
        "# Run `x`", "", "speed < 3 m/s, <b>not bold</b>", "",
        "| quantity | value |", "| --- | ---: |", "| mass | 1.5 |", "| count | 3 |", "",
        "![a](a.png)", "", "![b](figures/größe.png)", "",
    ])  # fmt: skip
    page_path = write_markdown_report(tmp_path / "report.md", markdown)
    assert page_path == tmp_path / "report.html"
    assert (tmp_path / "report.md").read_text(encoding="utf-8") == markdown
    page = assert_self_contained(tmp_path / "report.md")
    assert len(page.images) == 2 and page.tables == 1 and page.rows == 3
    html = page_path.read_text(encoding="utf-8")
    assert "<title>Run x</title>" in html and '<td style="text-align:right">1.5</td>' in html
    assert "&lt;b&gt;not bold&lt;/b&gt;" in html and "speed &lt; 3 m/s" in html


def test_a_figure_the_report_links_but_nobody_wrote_is_named(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match=r"report\.md: the figure gone\.png is not in"):
        write_markdown_report(tmp_path / "report.md", "# R\n\n![gone](gone.png)\n")


def test_compare_writes_its_page(tmp_path: Path) -> None:
    """perga compare on a short single-granule run: four figures in figures/, the tables."""
    run, report = tmp_path / "run", tmp_path / "compare"
    case = str(ROOT / "cases" / "single-granule.toml")
    assert main(["run", case, "-o", str(run), "--quiet", "--set", "solver.duration=0.03"]) == 0
    assert main(["compare", str(run), "-o", str(report)]) == 0
    assert len(figures_of(report / "report.md")) >= 4
    assert assert_self_contained(report / "report.md").tables >= 2


def _toy_window(directory: Path) -> WindowResult:
    """A 2 × 2 window of the bee-bread separator with made-up metrics, two replicates each."""
    window = window_study(
        ROOT / "cases" / "bee-bread-separator.toml",
        ["rotor.rpm=1000:1500:2", "hammers.mass=0.05:0.1:2"],
        replicates=2,
    )
    xs, ys = window.grid()
    rows = [
        {window.axes[0]: x, window.axes[1]: y, "status": "ok",
         "released_fraction": 0.5 + x / 4000 + k / 100, "damaged_fraction": y / 2 + k / 100,
         "throughput": x / 1e5, "energy_per_kg": 1e3 * y, "ledger_closure": 0.0}
        for x in xs for y in ys for k in range(2)
    ]  # fmt: skip
    points = aggregate(rows, window.axes, (xs, ys))
    best = best_point(points, window.release_target, window.damage_limit)
    result = WindowResult(window, points, best, trade_offs(points), trends(window, points),
                          foundations(window), rows, len(rows), 0, 0)  # fmt: skip
    directory.mkdir()
    write_maps(result, directory)
    write_trade_offs(result, directory)
    write_report(result, directory)
    return result


def test_window_writes_its_page_and_names_the_case_from_its_folder(tmp_path: Path) -> None:
    out = tmp_path / "window"
    _toy_window(out)
    assert figures_of(out / "report.md") == ["window.png", "trade-offs.png"]
    assert assert_self_contained(out / "report.md").tables == 3
    (named,) = re.findall(r"Case `([^`]+)`", (out / "report.md").read_text(encoding="utf-8"))
    assert not Path(named).is_absolute()
    assert (out / named).resolve() == (ROOT / "cases" / "bee-bread-separator.toml").resolve()


def test_window_under_a_posterior_writes_its_page(tmp_path: Path) -> None:
    """The toy of tests/studies/test_window_odds.py: 4 draws × 2 seeds at 3 × 2 settings."""
    window = window_study(odds.CASE, odds.SETS, release_target=0.9, damage_limit=0.05)
    sample = tmp_path / "posterior.parquet"
    pq.write_table(pa.table({odds.KEY: [0.05, 0.055, 0.06, 0.065]}), sample)
    posterior = read_posterior(sample, 4, 0)
    out = tmp_path / "odds"
    result = run_odds(window, posterior, 2, out, workers=1, function=odds.toy_run)
    write_odds_map(result, out)
    write_odds_report(result, assumed_values(window, posterior.keys), [], out)
    assert figures_of(out / "report.md") == ["odds.png"]
    assert assert_self_contained(out / "report.md").tables == 1


def test_adaptive_window_writes_its_page(tmp_path: Path) -> None:
    """The toy of tests/studies/test_window_adaptive.py on a 3 × 3 grid, 9 runs."""
    window = window_study(adaptive.CASE, ["rotor.rpm=400:1600:3", "hammers.mass=0.025:0.1:3"])
    out = tmp_path / "adaptive"
    out.mkdir()
    result = run_adaptive(window, out, budget=9, workers=1, function=adaptive.toy_run)
    write_adaptive(result, out)
    assert figures_of(out / "adaptive.md") == ["adaptive.png"]
    assert assert_self_contained(out / "adaptive.md").tables == 0


def test_accuracy_writes_its_page(tmp_path: Path) -> None:
    """The accuracy report's tables and one figure per reference (a made-up study's rows)."""
    rows = [
        Row(reference=reference, model="rigid", family="rigid", setting=f"substeps={n}",
            dt=dt, machine_dt=dt, t_c=math.inf, iterations=10, steps_per_contact=math.nan,
            granule_substeps=1, error=0.1 * n, wall_per_sim=1e3 / n, steps=100 * n)
        for reference in ("restitution", "hinged") for n, dt in ((1, 1e-4), (2, 5e-5))
    ]  # fmt: skip
    paths = write_outputs(StudyResult(rows, 1.0, (0.5, 0.5)), tmp_path)
    assert tmp_path / "accuracy.html" in paths
    assert figures_of(tmp_path / "accuracy.md") == ["restitution.png", "hinged.png"]
    assert assert_self_contained(tmp_path / "accuracy.md").tables == 3
