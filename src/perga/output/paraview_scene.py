"""The ParaView scene of a run: a pvpython script, never imported by perga. Its text, with a call
of :func:`show_run` for the run, is each run's ``vtk/paraview_state.py``
(:mod:`perga.output.paraview_state`), which ParaView opens as a Python state (File > Load State,
or ``paraview --state=RUN/vtk/paraview_state.py``) and ``postprocess/paraview/render_run.py``
builds its 2-D picture from.

The scene, from the files of :mod:`perga.output.vtk`: granules at their true size as filled
discs (``Glyph With Custom Source``: a 32-gon ``Disk`` of radius 0.5 scaled by ``radius`` with
ScaleFactor 2) coloured by ``speed`` on Viridis (no greys, so they stand out from the machine)
from 0 to the run's top speed; hammers as grey surfaces; the rotor disc, under them, as its grey
outline; the chamber as dark lines; all at the run's last frame. Each file is a source of its
own, named in the Pipeline Browser, so that any part can be hidden, recoloured or filtered. 2-D
interaction, the camera on the chamber.
"""

from pathlib import Path

from paraview import simple as pv

GREY = [0.5, 0.5, 0.5]
DARK = [0.2, 0.2, 0.2]
CIRCLE_SIDES = 32
"""Sides of the polygon each granule is drawn as (its area 0.6 % short of the circle's)."""


def show_run(vtk: Path, speed_max: float, chamber: bool) -> None:
    """Open the series in ``vtk`` (a run's ``vtk/`` folder) in the active render view:
    granules coloured from 0 to ``speed_max`` (m/s), and the chamber if it was written."""
    view = pv.GetActiveViewOrCreate("RenderView")
    view.InteractionMode = "2D"
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]

    rotor = pv.PVDReader(registrationName="rotor", FileName=str(vtk / "rotor.pvd"))
    _plain(pv.Show(rotor, view), "Wireframe", GREY)
    hammers = pv.PVDReader(registrationName="hammers", FileName=str(vtk / "hammers.pvd"))
    _plain(pv.Show(hammers, view), "Surface", GREY)
    if chamber:
        wall = pv.XMLUnstructuredGridReader(
            registrationName="chamber", FileName=[str(vtk / "chamber.vtu")]
        )
        shown = _plain(pv.Show(wall, view), "Surface", DARK)
        shown.LineWidth = 2.0

    granules = pv.PVDReader(registrationName="granules", FileName=str(vtk / "granules.pvd"))
    disc = pv.Disk(
        registrationName="unit disc",
        InnerRadius=0.0,
        OuterRadius=0.5,
        CircumferentialResolution=CIRCLE_SIDES,
    )
    discs = pv.GlyphWithCustomSource(
        registrationName="granules at true size", Input=granules, GlyphSource=disc
    )
    discs.OrientationArray = ["POINTS", "No orientation array"]
    discs.ScaleArray = ["POINTS", "radius"]
    discs.ScaleFactor = 2.0
    discs.GlyphMode = "All Points"
    shown = _unlit(pv.Show(discs, view))
    pv.Hide(granules, view)
    pv.ColorBy(shown, ("POINTS", "speed"))
    lut = pv.GetColorTransferFunction("speed")
    lut.ApplyPreset("Viridis (matplotlib)", True)
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(0.0, max(speed_max, 1e-9))
    pv.GetOpacityTransferFunction("speed").RescaleTransferFunction(0.0, max(speed_max, 1e-9))
    shown.SetScalarBarVisibility(view, True)
    bar = pv.GetScalarBar(lut, view)
    bar.Title, bar.ComponentTitle = "speed, m/s", ""
    bar.TitleColor = bar.LabelColor = [0.0, 0.0, 0.0]

    scene = pv.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = scene.EndTime  # the last frame: at t = 0 every granule is at rest
    pv.SetActiveSource(discs)
    view.ResetCamera()
    pv.Render(view)


def _unlit(shown):
    """``shown`` in its own colours, as the colour bar gives them: no shading (a flat scene)."""
    shown.Ambient, shown.Diffuse = 1.0, 0.0
    return shown


def _plain(shown, style: str, colour: list[float]):
    """``shown`` drawn as ``style`` in one ``colour``, not coloured by data."""
    shown.SetRepresentationType(style)
    shown.ColorArrayName = ["POINTS", ""]
    shown.AmbientColor = shown.DiffuseColor = colour
    return _unlit(shown)
