"""2-D part outlines from files, validated: a points file (x y per line), an SVG path or
polygon, or a DXF LWPOLYLINE/POLYLINE. Coordinates are in declared units, scaled to metres.

Validation: coordinates finite and within ±10 m, at least 3 distinct vertices, closed, not
self-intersecting, the hinge (if given) strictly inside; the outline is returned
counter-clockwise, near-duplicate and collinear vertices removed.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from perga.geometry.polygon import (
    FloatArray,
    as_points,
    clean,
    contains,
    counter_clockwise,
    self_intersection,
)
from perga.geometry.units import GeometryError, check_extent, unit_scale

POINTS_SUFFIXES = (".txt", ".xy", ".pts", ".csv")


@dataclass(frozen=True)
class Outline:
    """vertices: (n, 2) m, counter-clockwise, simple; source: where it came from."""

    vertices: FloatArray
    source: str


def validate_outline(
    points: ArrayLike, source: str, closed: bool = True, hinge: ArrayLike | None = None
) -> Outline:
    """Check and normalise raw outline vertices (m); GeometryError naming ``source``."""
    raw = as_points(points)
    check_extent(raw, source)
    if not closed:
        raise GeometryError(
            f"{source}: the outline is not closed (close the path or polyline, or repeat "
            "the first vertex at the end)"
        )
    vertices = clean(raw) if len(raw) else raw
    if len(vertices) < 3:
        raise GeometryError(
            f"{source}: an outline needs at least 3 distinct, non-collinear vertices "
            f"(got {len(vertices)})"
        )
    crossing = self_intersection(vertices)
    if crossing is not None:
        n = len(vertices)
        i, j = crossing

        def edge(k: int) -> str:
            a, b = vertices[k], vertices[(k + 1) % n]
            return f"edge {k} ({a[0]:.6g}, {a[1]:.6g})-({b[0]:.6g}, {b[1]:.6g}) m"

        raise GeometryError(f"{source}: the outline intersects itself: {edge(i)} meets {edge(j)}")
    vertices = counter_clockwise(vertices)
    if hinge is not None:
        h = np.asarray(hinge, dtype=float)
        if not contains(vertices, h):
            raise GeometryError(
                f"{source}: the hinge ({h[0]:.6g}, {h[1]:.6g}) m is not inside the part"
            )
    return Outline(vertices, source)


def _closing(points: list[list[float]]) -> bool:
    return len(points) > 1 and np.allclose(points[0], points[-1], rtol=0, atol=0)


def parse_points(text: str, source: str) -> list[list[float]]:
    """'x y' (or 'x, y') per line; blank lines and lines starting with '#' skipped."""
    points = []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        fields = line.replace(",", " ").split()
        try:
            if len(fields) != 2:
                raise ValueError
            points.append([float(fields[0]), float(fields[1])])
        except ValueError:
            raise GeometryError(
                f"{source}: line {number}: expected two numbers 'x y' (got {line!r})"
            ) from None
    return points


_SVG_TOKEN = re.compile(r"[A-Za-z]|[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def parse_svg_path(d: str, source: str) -> tuple[list[list[float]], bool]:
    """Vertices and closed flag of one SVG path ``d`` of M/L/H/V/Z commands (either case)."""
    tokens = _SVG_TOKEN.findall(d)
    points: list[list[float]] = []
    closed = False
    x = y = 0.0
    command = ""
    k = 0

    def number() -> float:
        nonlocal k
        if k >= len(tokens) or tokens[k].isalpha():
            raise GeometryError(f"{source}: SVG path: command {command!r} is missing a number")
        k += 1
        return float(tokens[k - 1])

    while k < len(tokens):
        if tokens[k].isalpha():
            command = tokens[k]
            k += 1
            if command in "Zz":
                closed = True
                continue
            if command not in "MmLlHhVv":
                raise GeometryError(
                    f"{source}: SVG path command {command!r} is not supported (only straight "
                    "segments: M L H V Z; flatten curves and arcs to line segments)"
                )
            if command in "Mm" and points:
                raise GeometryError(f"{source}: SVG path has several sub-paths: one outline only")
        elif not command or command in "Zz":
            raise GeometryError(f"{source}: SVG path: number {tokens[k]!r} without a command")
        relative = command.islower()
        kind = command.upper()
        if kind in "ML":
            dx, dy = number(), number()
            x, y = (x + dx, y + dy) if relative else (dx, dy)
            command = "l" if command == "m" else "L" if command == "M" else command
        elif kind == "H":
            dx = number()
            x = x + dx if relative else dx
        else:
            dy = number()
            y = y + dy if relative else dy
        points.append([x, y])
    return points, closed


def parse_svg(text: str, source: str) -> tuple[list[list[float]], bool]:
    """The single <path> or <polygon> of an SVG file; y is flipped (SVG's y points down)."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as error:
        raise GeometryError(f"{source}: not valid SVG/XML ({error})") from None
    shapes = [e for e in root.iter() if e.tag.rsplit("}", 1)[-1] in ("path", "polygon")]
    if len(shapes) != 1:
        raise GeometryError(
            f"{source}: expected exactly one <path> or <polygon> (found {len(shapes)})"
        )
    if any("transform" in e.attrib for e in root.iter()):
        raise GeometryError(f"{source}: SVG transforms are not supported: apply them first")
    shape = shapes[0]
    if shape.tag.endswith("polygon"):
        values = [float(v) for v in _SVG_TOKEN.findall(shape.get("points", ""))]
        points, closed = [list(p) for p in zip(values[::2], values[1::2], strict=False)], True
    else:
        points, closed = parse_svg_path(shape.get("d", ""), source)
    return [[px, -py] for px, py in points], closed


def _dxf_entities(text: str, source: str) -> list[tuple[str, list[tuple[str, str]]]]:
    """(type, [(group code, value), ...]) for each '0' group of an ASCII DXF file."""
    lines = [line.strip() for line in text.splitlines()]
    entities: list[tuple[str, list[tuple[str, str]]]] = []
    for i in range(0, len(lines) - 1, 2):
        code, value = lines[i], lines[i + 1]
        if code == "0":
            entities.append((value, []))
        elif entities:
            entities[-1][1].append((code, value))
    if not entities:
        raise GeometryError(f"{source}: not an ASCII DXF file (no entities)")
    return entities


def _dxf_vertices(groups: list[tuple[str, str]], source: str) -> list[list[float]]:
    points: list[list[float]] = []
    try:
        for code, value in groups:
            if code == "10":
                points.append([float(value), float("nan")])
            elif code == "20" and points:
                points[-1][1] = float(value)
            elif code == "42" and float(value) != 0.0:
                raise GeometryError(
                    f"{source}: DXF polyline has arc segments (bulge): flatten them to lines"
                )
    except ValueError:
        raise GeometryError(f"{source}: DXF: bad vertex coordinate in {groups!r}") from None
    if any(np.isnan(p[1]) for p in points):
        raise GeometryError(f"{source}: DXF vertex with x (code 10) but no y (code 20)")
    return points


def _dxf_closed(groups: list[tuple[str, str]]) -> bool:
    return any(code == "70" and int(value) & 1 for code, value in groups)


def parse_dxf(text: str, source: str) -> tuple[list[list[float]], bool]:
    """The single LWPOLYLINE, or POLYLINE with its VERTEX entities, of an ASCII DXF file:
    vertices from group codes 10/20, closed from bit 1 of group code 70."""
    entities = _dxf_entities(text, source)
    polylines: list[tuple[list[list[float]], bool]] = []
    for k, (kind, groups) in enumerate(entities):
        if kind == "LWPOLYLINE":
            polylines.append((_dxf_vertices(groups, source), _dxf_closed(groups)))
        elif kind == "POLYLINE":
            vertex_groups = []
            for following, vertex in entities[k + 1 :]:
                if following != "VERTEX":
                    break
                vertex_groups.extend(vertex)
            polylines.append((_dxf_vertices(vertex_groups, source), _dxf_closed(groups)))
    if len(polylines) != 1:
        raise GeometryError(
            f"{source}: expected exactly one LWPOLYLINE or POLYLINE (found {len(polylines)})"
        )
    return polylines[0]


def read_outline(path: str | Path, units: str, hinge: ArrayLike | None = None) -> Outline:
    """A validated outline (m) from a points file (.txt .xy .pts .csv), .svg or .dxf declared in
    ``units`` (e.g. 'mm'); ``hinge`` (m, same frame after scaling) must lie inside the part.
    Points files are closed implicitly; SVG paths need Z (or a repeated first point), DXF
    polylines the closed flag (or a repeated first point)."""
    source = str(path)
    scale = unit_scale(units, source)
    try:
        text = Path(path).read_text()
    except OSError as error:
        raise GeometryError(f"{source}: cannot read ({error.strerror})") from None
    suffix = Path(path).suffix.lower()
    if suffix in POINTS_SUFFIXES:
        points, closed = parse_points(text, source), True
    elif suffix == ".svg":
        points, closed = parse_svg(text, source)
    elif suffix == ".dxf":
        points, closed = parse_dxf(text, source)
    else:
        raise GeometryError(
            f"{source}: unknown outline format {suffix!r} "
            f"(use {', '.join(POINTS_SUFFIXES)}, .svg or .dxf)"
        )
    closed = closed or _closing(points)
    return validate_outline(
        np.array(points, dtype=float).reshape(-1, 2) * scale, source, closed, hinge
    )
