"""Regenerate the bundled geometry files in this folder (all lengths in mm).

    python geometry/make_bundled.py [OUT_DIR]

Hammers are drawn in the hammer frame: hinge at the origin, hammer axis along +x, the rotor
plane at z = 0 (meshes span z = -5 .. 5 mm). The rotor disc and chambers are centred on the
rotor axis.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import trimesh

from perga.geometry.extrude import extrude

HERE = Path(__file__).resolve().parent
THICKNESS = 10.0  # mm, hammers and rotor disc
ROTOR_RADIUS, ROTOR_SECTIONS = 150.0, 256  # mm, sides of the disc polygon
HOLE_RADIUS, HOLE_SECTIONS, HOLE_PITCH_RADIUS = 8.0, 48, 120.0  # mm
CHAMBER_RADIUS = 300.0  # mm


def arc(centre: tuple[float, float], radius: float, start: float, stop: float, n: int):
    """n + 1 points from angle start to stop (rad) on a circle, mm."""
    t = np.linspace(start, stop, n + 1)
    return np.c_[centre[0] + radius * np.cos(t), centre[1] + radius * np.sin(t)]


def plate_hammer() -> trimesh.Trimesh:
    """150 x 50 x 10 mm plate, hinge 15 mm from its inner end."""
    box = trimesh.creation.box(extents=[150.0, 50.0, THICKNESS])
    box.apply_translation([60.0, 0.0, 0.0])
    return box


def stepped_outline() -> np.ndarray:
    """A 50 mm wide shank (x = -15 .. 75 mm) and a 70 mm wide head (x = 75 .. 135 mm)."""
    return np.array(
        [[-15, -25], [75, -25], [75, -35], [135, -35], [135, 35], [75, 35], [75, 25], [-15, 25]],
        dtype=float,
    )


def rounded_outline(segments: int = 32) -> np.ndarray:
    """A 50 mm wide bar from x = -15 mm to 110 mm ending in a half disc of radius 25 mm."""
    head = arc((110.0, 0.0), 25.0, -np.pi / 2, np.pi / 2, segments)
    return np.vstack([[[-15.0, -25.0]], head, [[-15.0, 25.0]]])


def disc_outline() -> np.ndarray:
    return arc((0.0, 0.0), ROTOR_RADIUS, 0.0, 2 * np.pi, ROTOR_SECTIONS)[:-1]


def hole_centres(count: int) -> np.ndarray:
    angles = 2 * np.pi * np.arange(count) / count
    return HOLE_PITCH_RADIUS * np.c_[np.cos(angles), np.sin(angles)]


def hole_outline(centre: np.ndarray) -> np.ndarray:
    """A clockwise hinge hole polygon, mm."""
    return arc(tuple(centre), HOLE_RADIUS, 0.0, -2 * np.pi, HOLE_SECTIONS)[:-1]


def rotor_disc(holes: int) -> trimesh.Trimesh:
    """Disc of radius 150 mm, 10 mm thick, ``holes`` hinge holes of radius 8 mm at 120 mm."""
    loops = [hole_outline(c) for c in hole_centres(holes)]
    return extrude(disc_outline(), THICKNESS, loops, z0=-THICKNESS / 2)


def screen_chamber_outline(segments: int = 160) -> np.ndarray:
    """Round chamber of radius 300 mm with a 150 mm wide outlet channel at the bottom closed
    by the screen at y = -380 mm."""
    half = np.arcsin(75.0 / CHAMBER_RADIUS)
    wall = arc((0.0, 0.0), CHAMBER_RADIUS, -np.pi / 2 + half, 1.5 * np.pi - half, segments)
    return np.vstack([wall, [[wall[-1, 0], -380.0], [wall[0, 0], -380.0]]])


def svg_path(points: np.ndarray, relative: bool) -> str:
    """An SVG file with one closed path (y flipped: SVG's y points down)."""
    p = points * [1.0, -1.0]
    if relative:
        steps = " ".join(f"l {dx:.9g} {dy:.9g}" for dx, dy in np.diff(p, axis=0))
    else:
        steps = " ".join(f"L {x:.9g} {y:.9g}" for x, y in p[1:])
    d = f"M {p[0, 0]:.9g} {p[0, 1]:.9g} {steps} Z"
    return f'<svg xmlns="http://www.w3.org/2000/svg" units="mm">\n  <path d="{d}"/>\n</svg>\n'


def dxf_lwpolyline(points: np.ndarray) -> str:
    """A minimal ASCII DXF with one closed LWPOLYLINE."""
    rows = ["0", "SECTION", "2", "ENTITIES", "0", "LWPOLYLINE", "8", "0"]
    rows += ["90", str(len(points)), "70", "1"]
    for x, y in points:
        rows += ["10", f"{x:.9g}", "20", f"{y:.9g}"]
    rows += ["0", "ENDSEC", "0", "EOF"]
    return "\n".join(rows) + "\n"


def points_file(points: np.ndarray, title: str) -> str:
    return f"# {title}\n# x y, mm\n" + "".join(f"{x:.9g} {y:.9g}\n" for x, y in points)


def main(out: Path = HERE) -> None:
    out.mkdir(parents=True, exist_ok=True)
    plate_hammer().export(out / "plate_hammer.stl")
    extrude(stepped_outline(), THICKNESS, z0=-THICKNESS / 2).export(out / "stepped_hammer.stl")
    (out / "rounded_hammer.svg").write_text(svg_path(rounded_outline(), relative=False))
    (out / "rounded_hammer.dxf").write_text(dxf_lwpolyline(rounded_outline()))
    rotor_disc(4).export(out / "rotor_disc_4_holes.stl")
    rotor_disc(8).export(out / "rotor_disc_8_holes.stl")
    (out / "chamber_round.txt").write_text(
        points_file(arc((0, 0), CHAMBER_RADIUS, 0, 2 * np.pi, 180)[:-1], "round chamber")
    )
    (out / "chamber_screen.svg").write_text(svg_path(screen_chamber_outline(), relative=True))


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
