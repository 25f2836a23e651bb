"""A Markdown report and, beside it, the same report as one self-contained HTML page: the
Markdown rendered by markdown-it-py (CommonMark with GitHub's tables; raw HTML in the text is
shown as text), every image it links read from its file and embedded as a base64 data URI, and
a small inline stylesheet, so the page can be mailed or moved alone."""

from __future__ import annotations

import base64
import mimetypes
from html import escape
from pathlib import Path
from urllib.parse import unquote

from markdown_it import MarkdownIt
from markdown_it.token import Token

STYLE = """body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto;
  padding: 0 1rem; line-height: 1.45; color: #222; }
table { border-collapse: collapse; margin: 1rem 0; }
th, td { border: 1px solid #bbb; padding: 0.2rem 0.5rem; }
th { background: #eee; }
code { background: #f3f3f3; padding: 0 0.2rem; }
img { max-width: 100%; }"""
"""The page's stylesheet, inline."""


def _parser() -> MarkdownIt:
    """CommonMark with tables; raw HTML escaped (a report's "<" is text)."""
    return MarkdownIt("commonmark", {"html": False}).enable("table")


def data_uri(path: Path) -> str:
    """The file ``path`` as a ``data:`` URI (RFC 2397), base64, its media type from its suffix."""
    media = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
    return f"data:{media};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"


def _embed_images(tokens: list[Token], source: Path) -> None:
    """Every image of ``tokens`` given its file (relative to the report ``source``'s folder)
    as a data URI; FileNotFoundError naming ``source`` and the image for one that is missing."""
    for token in tokens:
        for child in token.children or ():
            if child.type != "image":
                continue
            src = str(child.attrs["src"])
            if src.startswith("data:"):
                continue
            image = source.parent / unquote(src)  # markdown-it percent-encodes the address
            if not image.is_file():
                raise FileNotFoundError(f"{source}: the figure {src} is not in {source.parent}")
            child.attrs["src"] = data_uri(image)


def _title(tokens: list[Token], default: str) -> str:
    """The text of the first heading, else ``default``."""
    for k, token in enumerate(tokens):
        if token.type == "heading_open":
            return "".join(c.content for c in tokens[k + 1].children or ())
    return default


def html_page(markdown: str, source: Path) -> str:
    """The Markdown report ``markdown``, to be written at ``source`` (its images are relative
    to that file's folder), as a self-contained HTML page."""
    parser = _parser()
    tokens = parser.parse(markdown)
    _embed_images(tokens, source)
    body = parser.renderer.render(tokens, parser.options, {})
    title = escape(_title(tokens, source.stem))
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{title}</title>\n<style>\n{STYLE}\n</style>\n</head>\n<body>\n{body}</body>\n"
        "</html>\n"
    )


def write_markdown_report(path: Path, markdown: str) -> Path:
    """Write the Markdown report ``path`` (``markdown``, its images already written beside
    it) and the same report as a self-contained HTML page with the same name, ``.html``;
    returns the HTML page's path."""
    path.write_text(markdown, encoding="utf-8")
    page = path.with_suffix(".html")
    page.write_text(html_page(markdown, path), encoding="utf-8")
    return page
