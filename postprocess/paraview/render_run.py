"""Open a perga run in ParaView and save a PNG (or an animation): pvbatch/pvpython script.

    xvfb-run -a pvbatch postprocess/paraview/render_run.py RUN [--time T] [-o PNG]
        [--animation DIR] [--gaussian] [--state FILE.pvsm] [--no-bar]

Reads RUN/vtk/ (written by perga.output.vtk): granules drawn at their true size as filled
circles (``Glyph``, '2D Glyph' circle scaled by ``radius``, ScaleFactor 2 = diameter) coloured
by ``speed``; hammers as grey surfaces, the rotor disc and the chamber as lines. ``--gaussian``
uses the Point Gaussian representation instead (the interactive choice; under Mesa/xvfb it
draws nothing, design notes section 6). ``--state`` saves the scene as a ParaView state file
for interactive use (File > Load State; "Search files under specified directory" re-targets it
to another run). Prints the time steps and granule arrays it found.
"""

import argparse
from pathlib import Path

from paraview import simple as pv


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--time", type=float, help="simulated time of the frame, s (default last)")
    parser.add_argument("-o", "--output", type=Path, help="PNG (default RUN/paraview.png)")
    parser.add_argument("--animation", type=Path, help="also save every frame into this folder")
    parser.add_argument("--gaussian", action="store_true", help="Point Gaussian granules")
    parser.add_argument("--no-bar", action="store_true", help="no colour bar")
    parser.add_argument(
        "--state", type=Path, help="also save a ParaView state file (.pvsm) of this scene"
    )
    parser.add_argument("--size", type=int, nargs=2, default=(900, 900), metavar=("W", "H"))
    args = parser.parse_args()
    vtk = args.run / "vtk"

    granules = pv.PVDReader(FileName=str(vtk / "granules.pvd"))
    machine = pv.PVDReader(FileName=str(vtk / "machine.pvd"))
    times = list(granules.TimestepValues)
    arrays = sorted(granules.PointData.keys())
    print(f"time steps: {len(times)} ({times[0]:.6g} .. {times[-1]:.6g} s)")
    print("granule arrays: " + ", ".join(arrays))

    view = pv.CreateView("RenderView")
    view.ViewSize = list(args.size)
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    view.OrientationAxesVisibility = 0
    if args.gaussian:
        shown = pv.Show(granules, view)
        shown.SetRepresentationType("Point Gaussian")
        shown.ShaderPreset = "Plain circle"
        shown.ScaleByArray = 1
        shown.SetScaleArray = ["POINTS", "radius"]
        shown.GaussianRadius = 1.0
    else:
        glyph = pv.Glyph(Input=granules, GlyphType="2D Glyph")
        glyph.GlyphType.GlyphType = "Circle"
        glyph.GlyphType.Filled = 1
        glyph.ScaleArray = ["POINTS", "radius"]
        glyph.ScaleFactor = 2.0
        glyph.GlyphMode = "All Points"
        shown = pv.Show(glyph, view)
    pv.ColorBy(shown, ("POINTS", "speed"))
    shown.SetScalarBarVisibility(view, not args.no_bar)
    lut = pv.GetColorTransferFunction("speed")
    lut.ApplyPreset("Viridis (matplotlib)", True)  # no greys: granules stand out from hammers
    bar = pv.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "speed, m/s", ""
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]
    # hammers (cell id >= 0) as grey surfaces; the rotor disc (id -1), under the granules, as
    # its outline only
    for lower, upper, style in ((0.0, 1e9, "Surface"), (-1.0, -1.0, "Wireframe")):
        part = pv.Threshold(Input=machine, Scalars=["CELLS", "id"])
        part.LowerThreshold, part.UpperThreshold = lower, upper
        machine_shown = pv.Show(part, view)
        machine_shown.SetRepresentationType(style)
        machine_shown.ColorArrayName = ["POINTS", ""]
        machine_shown.AmbientColor = machine_shown.DiffuseColor = [0.5, 0.5, 0.5]
    chamber_file = vtk / "chamber.vtu"
    if chamber_file.exists():
        chamber = pv.Show(pv.XMLUnstructuredGridReader(FileName=[str(chamber_file)]), view)
        chamber.ColorArrayName = ["POINTS", ""]
        chamber.AmbientColor = chamber.DiffuseColor = [0.2, 0.2, 0.2]
        chamber.LineWidth = 2.0

    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    time = times[-1] if args.time is None else min(times, key=lambda t: abs(t - args.time))
    scene.AnimationTime = time
    shown.RescaleTransferFunctionToDataRange(False, True)
    view.InteractionMode = "2D"
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


if __name__ == "__main__":
    main()
