"""2-D outlines from points, SVG and DXF files, and their validation errors."""

from __future__ import annotations

import numpy as np
import pytest

from perga.geometry import GeometryError, read_outline
from perga.geometry.polygon import signed_area

SQUARE_MM = [(0, 0), (10, 0), (10, 10), (0, 10)]


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


def dxf(points, closed=True, kind="LWPOLYLINE"):
    rows = ["0", "SECTION", "2", "ENTITIES"]
    if kind == "LWPOLYLINE":
        rows += ["0", "LWPOLYLINE", "70", "1" if closed else "0"]
        for x, y in points:
            rows += ["10", str(x), "20", str(y)]
    else:
        rows += ["0", "POLYLINE", "70", "1" if closed else "0"]
        for x, y in points:
            rows += ["0", "VERTEX", "10", str(x), "20", str(y)]
        rows += ["0", "SEQEND"]
    return "\n".join([*rows, "0", "ENDSEC", "0", "EOF"]) + "\n"


@pytest.mark.parametrize(
    ("name", "text"),
    [
        ("sq.txt", "# square\n0 0\n0 10\n10 10\n10 0\n"),
        ("sq.csv", "0, 0\n5, 0\n10, 0\n10, 10\n0, 10\n0, 0\n"),  # collinear + closing repeat
        ("sq.svg", '<svg xmlns="http://www.w3.org/2000/svg"><path d="M0 0 H10 V10 H0 Z"/></svg>'),
        ("sq_rel.svg", '<svg><path d="m 0,0 10,0 0,10 -10,0 z"/></svg>'),
        ("sq_lv.svg", '<svg><path d="M 0 0 l 10 0 v 10 h -10 L 0 0"/></svg>'),
        ("sq_poly.svg", '<svg><polygon points="0,0 10,0 10,10 0,10"/></svg>'),
        ("sq.dxf", dxf(SQUARE_MM)),
        ("sq_old.dxf", dxf(SQUARE_MM, kind="POLYLINE")),
    ],
)
def test_formats_give_the_same_ccw_square_in_metres(tmp_path, name, text):
    outline = read_outline(
        write(tmp_path, name, text),
        "mm",
        hinge=(0.005, 0.005 * (-1 if name.endswith(".svg") else 1)),
    )
    assert len(outline.vertices) == 4
    assert signed_area(outline.vertices) == pytest.approx(1e-4, rel=1e-12)
    assert np.abs(outline.vertices).max() == pytest.approx(0.010)


BAD = [
    ("two.txt", "0 0\n1 1\n", "at least 3 distinct"),
    ("line.txt", "0 0\n1 1\n2 2\n", "at least 3 distinct"),
    ("word.txt", "0 0\n1 x\n", r"line 2: expected two numbers"),
    ("bow.txt", "0 0\n10 10\n10 0\n0 10\n", r"intersects itself: edge 0 .* meets edge 2"),
    ("open.svg", '<svg><path d="M0 0 L10 0 L10 10"/></svg>', "not closed"),
    ("curve.svg", '<svg><path d="M0 0 C 1 1 2 2 3 0 Z"/></svg>', "command 'C' is not supported"),
    ("two.svg", "<svg><path d='M0 0 L1 0 L0 1 Z'/><path d='M0 0 L1 0 L0 1 Z'/></svg>", "found 2"),
    ("open.dxf", dxf(SQUARE_MM, closed=False), "not closed"),
    ("none.dxf", "0\nSECTION\n0\nEOF\n", r"exactly one LWPOLYLINE or POLYLINE \(found 0\)"),
    ("shape.step", "", "unknown outline format '.step'"),
]


@pytest.mark.parametrize(("name", "text", "message"), BAD, ids=[b[0] for b in BAD])
def test_bad_outlines_are_refused_naming_the_file(tmp_path, name, text, message):
    with pytest.raises(GeometryError, match=rf"{name}: .*{message}"):
        read_outline(write(tmp_path, name, text), "mm")


def test_hinge_outside_the_part_is_refused(tmp_path):
    path = write(tmp_path, "l.txt", "0 0\n20 0\n20 10\n10 10\n10 20\n0 20\n")
    read_outline(path, "mm", hinge=(0.005, 0.015))
    for hinge in [(0.015, 0.015), (0.0, 0.005), (0.03, 0.0)]:  # notch, on the edge, far out
        with pytest.raises(GeometryError, match=r"l.txt: the hinge .* is not inside the part"):
            read_outline(path, "mm", hinge=hinge)
