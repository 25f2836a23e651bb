"""What a report's HTML page is checked by: it parses, every figure its Markdown links is in it
as a data URI of that file's bytes, nothing in it points at a file, and every table row of the
Markdown is a table row of the page (tests/test_html_report.py, tests/test_report.py)."""

from __future__ import annotations

import base64
import re
from html.parser import HTMLParser
from pathlib import Path

FIGURE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")
"""A Markdown image: ``![alt](file)``."""
DELIMITER = re.compile(r"^\|(\s*:?-+:?\s*\|)+\s*$")
"""A Markdown table's delimiter row: ``| --- | ---: |``."""


class Page(HTMLParser):
    """An HTML page's images, the other addresses it names, its tables and table rows."""

    def __init__(self) -> None:
        super().__init__()
        self.images: list[str] = []
        self.addresses: list[str] = []
        self.tables = self.rows = 0

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        found = dict(attrs)
        if tag == "img":
            self.images.append(found.get("src") or "")
        else:
            self.addresses += [v or "" for k, v in attrs if k in ("src", "href")]
        self.tables += tag == "table"
        self.rows += tag == "tr"


def figures_of(markdown: Path) -> list[str]:
    """The files the Markdown report links as images, in order."""
    return FIGURE.findall(markdown.read_text(encoding="utf-8"))


def assert_self_contained(markdown: Path) -> Page:
    """The HTML page beside ``markdown`` (same name, .html) holds the report whole: parsed by
    html.parser, every linked figure as ``data:image/png;base64,`` of its file's bytes, no
    other address, one table row per Markdown table row (header rows included)."""
    page = Page()
    page.feed(markdown.with_suffix(".html").read_text(encoding="utf-8"))
    page.close()
    expected = [
        "data:image/png;base64," + base64.b64encode((markdown.parent / f).read_bytes()).decode()
        for f in figures_of(markdown)
    ]
    assert page.images == expected, [src[:60] for src in page.images]
    assert page.addresses == []
    lines = markdown.read_text(encoding="utf-8").splitlines()
    table_rows = [line for line in lines if line.startswith("|")]
    assert page.tables == sum(bool(DELIMITER.match(line)) for line in table_rows)
    assert page.rows == len(table_rows) - page.tables
    return page
