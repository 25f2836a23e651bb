"""Each run's ParaView state, ``RUN/vtk/paraview_state.py``: the scene script
:mod:`perga.output.paraview_scene` (its text, read as package data, never imported: it needs
ParaView's Python) followed by the call that opens this run's series.

Opened by File > Load State (a Python state) or ``paraview --state=RUN/vtk/paraview_state.py``;
``pvpython``/``pvbatch`` run it as a script. It finds the series beside itself (``__file__``,
which ParaView sets when it loads a state), so a run moved elsewhere still opens, and two runs
of one case write the same bytes. Written at the first frame with the speeds seen so
far and again when the recorder closes with the run's top speed (the colour scale's end).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

NAME = "paraview_state.py"


def write(directory: Path, speed_max: float, chamber: bool) -> Path:
    """Write ``directory / NAME`` for the series in ``directory`` (a run's ``vtk/``), the
    granules coloured from 0 to ``speed_max`` (m/s); ``chamber``: ``chamber.vtu`` was written."""
    scene = resources.files("perga.output").joinpath("paraview_scene.py").read_text()
    call = (
        "\n\n# This run (written by perga): the series beside this file\n"
        f"show_run(Path(__file__).resolve().parent, speed_max={float(speed_max)!r}, "
        f"chamber={chamber!r})\n"
    )
    path = directory / NAME
    temporary = path.with_suffix(".tmp")
    temporary.write_text(scene + call)
    temporary.replace(path)
    return path
