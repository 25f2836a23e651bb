"""perga: bee-bread granules struck by hammers on a rotor, simulated and checked against theory.

The Python API (each name imported on first use, so that ``import perga`` stays light)::

    import perga

    case = perga.load_case("cases/separator.toml", overrides=["rotor.rpm=2000"])  # the file
    system = perga.compile_case(case)                 # the system, built once and checked
    sim = perga.Simulation(system)                    # stepped in memory
    sim.run(0.05)                                     # s
    frame = sim.frame()                               # the state now, read-only SI arrays
    frame.energy.closure, frame.granules.velocities   # the ledger, the granules' velocities

    summary = perga.simulate("cases/separator.toml", "runs/sep", overrides=["solver.duration=0.1"])
    run = perga.load_run("runs/sep")                  # case, summary, tables as numpy columns
    run.granules["speed"], run.dataframe("impacts")   # a DataFrame needs perga[notebook]
    perga.evaluate(run, "ledger_closure")             # a named metric (`perga metrics` lists them)

Studies (sweeps on Dask, calibration, the operating window) are in :mod:`perga.studies`;
``examples/`` has scripts that use this API (run by the tests).
"""

from importlib import import_module
from typing import Any

__version__ = "0.1.0"

_API = {
    "load_case": "perga.case",
    "CaseError": "perga.case",
    "compile_case": "perga.model.compile",
    "Simulation": "perga.engine.simulation",
    "simulate": "perga.run",
    "RunSummary": "perga.run",
    "load_run": "perga.stats.tables",
    "Run": "perga.stats.tables",
    "evaluate": "perga.stats.metrics",
}
"""Public name -> the module that defines it."""

__all__ = ["__version__", *_API]


def __getattr__(name: str) -> Any:
    if name in _API:
        return getattr(import_module(_API[name]), name)
    raise AttributeError(f"module 'perga' has no attribute {name!r}")
