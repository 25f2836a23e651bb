"""Every relative link in README.md and docs/**/*.md leads to a file that exists, and so does
every path under docs/ that a page names in its text."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
LINK = re.compile(r"\[[^\]]*\]\(<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\)")
"""A Markdown link or image, ``[text](target "title")``: its target."""
MENTION = re.compile(r"(?<![\w/.-])docs/[\w./-]*[\w/]")
"""A path under docs/ named in a page's text, from the repository's root."""
FENCE = re.compile(r"^```.*?^```", re.M | re.S)


def relative_links(text: str) -> list[str]:
    """The targets of ``text``'s links outside code blocks that are files of this repository:
    no scheme (``https:``, ``mailto:``), no bare ``#anchor``; the ``#anchor`` of a file cut."""
    targets = LINK.findall(FENCE.sub("", text))
    return [t.split("#")[0] for t in targets if not re.match(r"^[a-z][a-z0-9+.-]*:|#", t)]


def broken(page: Path) -> list[str]:
    """The links and docs/ paths of ``page`` that lead nowhere."""
    text = page.read_text(encoding="utf-8")
    links = [t for t in relative_links(text) if not (page.parent / t).exists()]
    mentions = [m for m in MENTION.findall(text) if not (ROOT / m).exists()]
    return links + mentions


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_every_link_of_the_page_resolves(page):
    """No link or named docs/ path of the page is broken."""
    assert not broken(page), f"{page.relative_to(ROOT)}: broken {broken(page)}"


def test_the_check_finds_a_broken_link_and_skips_what_is_not_a_file():
    """A link to a missing file is found (with its anchor cut), a web address, an anchor and a
    link inside a code block are not files."""
    text = (
        "[a](no/such/page.md#part) [b](https://example.org) [c](#here) ![d](img.png)\n"
        "```text\n[e](inside/code.md)\n```\n"
    )
    assert relative_links(text) == ["no/such/page.md", "img.png"]
