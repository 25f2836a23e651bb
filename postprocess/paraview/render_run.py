"""Open a perga run in ParaView and save a PNG (or an animation): pvbatch/pvpython script.

    xvfb-run -a pvbatch postprocess/paraview/render_run.py RUN [--time T] [-o PNG]
        [--animation DIR] [--gaussian] [--3d] [--state FILE.pvsm] [--no-bar]

The 2-D picture is the run's own ParaView state, RUN/vtk/paraview_state.py (written by perga
with each run, perga.output.paraview_scene): granules at their true size as filled discs
coloured by ``speed``, hammers grey, the rotor disc's outline, the chamber's lines.
``--gaussian`` draws the granules with the Point Gaussian representation instead (the
interactive choice; under Mesa/xvfb it draws nothing, design notes section 6). ``--state``
also saves the scene as a ParaView state file (.pvsm). Prints the time steps and granule arrays
it found.

``--3d`` renders the 3-D view of a run made with ``output.vtk_3d = true`` (perga.output.vtk3d)
from an oblique camera: hammers (orange) and rotor disc (grey) as lit surfaces extruded to
their thickness (the disc drawn 2 % thinner than written, so that a disc as thick as the
hammers does not share their faces), the chamber wall translucent, and the granules as
cylinders of their ``radius`` and ``thickness`` (a 'Cylinder' glyph turned onto z: ScaleArray
``radius``, ScaleFactor 2, height thickness/(2·radius) of the unit glyph, so a run of one
granule size and thickness is drawn exactly; with several, the mean ratio is used and a note
printed).
"""

import argparse
import runpy
import sys
from pathlib import Path

from paraview import simple as pv

HAMMER_3D = [0.85, 0.45, 0.15]
ROTOR_3D = [0.6, 0.62, 0.65]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--time", type=float, help="simulated time of the frame, s (default last)")
    parser.add_argument("-o", "--output", type=Path, help="PNG (default RUN/paraview.png)")
    parser.add_argument("--animation", type=Path, help="also save every frame into this folder")
    parser.add_argument("--gaussian", action="store_true", help="Point Gaussian granules")
    parser.add_argument(
        "--3d", dest="three_d", action="store_true", help="the 3-D view (output.vtk_3d runs)"
    )
    parser.add_argument("--no-bar", action="store_true", help="no colour bar")
    parser.add_argument(
        "--state", type=Path, help="also save a ParaView state file (.pvsm) of this scene"
    )
    parser.add_argument("--size", type=int, nargs=2, default=(900, 900), metavar=("W", "H"))
    args = parser.parse_args()
    vtk = args.run / "vtk"

    view = pv.CreateView("RenderView")
    view.ViewSize = list(args.size)
    pv.SetActiveView(view)
    if args.three_d:
        shown = scene_3d(vtk, view)
    else:
        state = vtk / "paraview_state.py"
        if not state.exists():
            sys.exit(f"{state} is missing: run the case again with this perga")
        runpy.run_path(str(state))
        shown = pv.GetDisplayProperties(pv.FindSource("granules at true size"), view)
        if args.gaussian:
            pv.Hide(pv.FindSource("granules at true size"), view)
            shown = gaussian(pv.FindSource("granules"), view)
    granules = pv.FindSource("granules")
    times = list(granules.TimestepValues)
    print(f"time steps: {len(times)} ({times[0]:.6g} .. {times[-1]:.6g} s)")
    print("granule arrays: " + ", ".join(sorted(granules.PointData.keys())))
    shown.SetScalarBarVisibility(view, not args.no_bar)

    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    time = times[-1] if args.time is None else min(times, key=lambda t: abs(t - args.time))
    scene.AnimationTime = time
    if args.three_d:  # the 2-D state's colours run from 0 to the run's top speed
        shown.RescaleTransferFunctionToDataRange(False, True)
    view.ResetCamera()
    output = args.output or args.run / "paraview.png"
    pv.SaveScreenshot(str(output), view, ImageResolution=list(args.size))
    print(f"wrote {output} (t = {time:.6g} s)")
    if args.state:
        pv.SaveState(str(args.state))
        print(f"wrote the state {args.state} (File > Load State in ParaView)")
    if args.animation:
        args.animation.mkdir(parents=True, exist_ok=True)
        pv.SaveAnimation(str(args.animation / "frame.png"), view, ImageResolution=list(args.size))
        print(f"wrote the animation frames into {args.animation}")


def gaussian(granules, view):
    """The granules as Point Gaussian circles of their radius, coloured as the discs are."""
    shown = pv.Show(granules, view)
    shown.SetRepresentationType("Point Gaussian")
    shown.ShaderPreset = "Plain circle"
    shown.ScaleByArray = 1
    shown.SetScaleArray = ["POINTS", "radius"]
    shown.GaussianRadius = 1.0
    pv.ColorBy(shown, ("POINTS", "speed"))
    return shown


def scene_3d(vtk, view):
    """The 3-D scene (module doc); the granules' display."""
    if not (vtk / "hammers3d.pvd").exists():
        sys.exit(f"{vtk / 'hammers3d.pvd'} is missing: run the case with output.vtk_3d = true")
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.OrientationAxesVisibility = 0
    granules = pv.PVDReader(registrationName="granules", FileName=str(vtk / "granules.pvd"))
    shown = pv.Show(cylinders(granules), view)
    pv.ColorBy(shown, ("POINTS", "speed"))
    lut = pv.GetColorTransferFunction("speed")
    lut.ApplyPreset("Viridis (matplotlib)", True)  # no greys: granules stand out from the disc
    bar = pv.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "speed, m/s", ""
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    # hammers orange (told apart from the viridis granules and the grey disc)
    for name, colour in (("hammers3d", HAMMER_3D), ("rotor3d", ROTOR_3D)):
        part = pv.PVDReader(registrationName=name, FileName=str(vtk / f"{name}.pvd"))
        part_shown = pv.Show(part, view)
        part_shown.ColorArrayName = ["POINTS", ""]
        part_shown.AmbientColor = part_shown.DiffuseColor = colour
    # a disc as thick as the hammers shares their faces: drawn 2 % thinner (display only), the
    # hammers' faces are the ones seen
    pv.GetDisplayProperties(pv.FindSource("rotor3d"), view).Scale = [1.0, 1.0, 0.98]
    if (vtk / "chamber3d.vtu").exists():
        wall = pv.XMLUnstructuredGridReader(FileName=[str(vtk / "chamber3d.vtu")])
        chamber = pv.Show(wall, view)
        chamber.ColorArrayName = ["POINTS", ""]
        chamber.AmbientColor = chamber.DiffuseColor = [0.2, 0.2, 0.2]
        chamber.Opacity = 0.3
    # oblique: from below the rotor's -y side, 50° above the plane, z up on the screen
    view.InteractionMode = "3D"
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraPosition = [0.0, -0.64, 0.77]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    return shown


def cylinders(granules):
    """The granules as cylinders (z axis) of their radius and thickness, from the points."""
    data = granules.PointData
    if "thickness" not in list(data.keys()):
        sys.exit("the granule frames have no 'thickness': run the case with output.vtk_3d = true")
    t_low, t_high = data["thickness"].GetRange()
    r_low, r_high = data["radius"].GetRange()
    if t_high - t_low > 1e-9 * t_high or r_high - r_low > 1e-9 * r_high:
        print("note: granules of several sizes: cylinders drawn with the mean thickness/radius")
    glyph = pv.Glyph(Input=granules, GlyphType="Cylinder")
    glyph.GlyphType.Resolution = 24
    # the unit cylinder (radius 0.5, axis y) scaled by 2·radius: height = 2·radius·Height
    glyph.GlyphType.Height = 0.5 * (t_low + t_high) / (r_low + r_high)
    glyph.GlyphTransform.Rotate = [90.0, 0.0, 0.0]  # axis y -> z
    glyph.ScaleArray = ["POINTS", "radius"]
    glyph.ScaleFactor = 2.0
    glyph.GlyphMode = "All Points"
    return glyph


if __name__ == "__main__":
    main()
