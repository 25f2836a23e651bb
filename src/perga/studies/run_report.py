"""``perga report RUN``: one run as a Markdown page with figures, and as one self-contained HTML
page (``RUN/report/``): how it ended, what it holds, and plots of the energy ledger's terms over
time, the granules' speeds at the first and last frame, the impacts over time and the granules'
paths (``perga render``'s); for a process run (comb, feed, damage or outlet) its population, the
process metrics in the designer's units and the process figure (``perga render --process``'s).
A figure or metric the run's tables cannot give is left out with the reason."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from perga.output.figures import new_figure, save
from perga.output.html_report import write_markdown_report
from perga.output.process_figure import process_figure
from perga.output.render import render
from perga.run.summary import ledger_closure_text, path_from
from perga.stats.metrics import METRICS, MetricUnavailableError, evaluate
from perga.stats.tables import Run, load_run
from perga.studies.user_units import metric_label

PROCESS_METRICS = ("released_fraction", "damaged_fraction", "throughput", "energy_per_kg")
"""The separator's figures of merit, shown for a process run."""

ENERGY_TERMS = ("drive_work", "contact_dissipation", "friction", "drag", "joint_correction",
                "inflow", "outflow")  # fmt: skip
"""The ledger's terms drawn over time (J), as energy.csv names them, beside the change of
kinetic energy since the start (the hammers' own kinetic energy would flatten the rest)."""


def _energy(run: Run, out: Path) -> str:
    e = run.energy
    if not e or not e["time"].size:
        return "no energy figure: energy.csv was not recorded (`output.record`)"
    fig, (terms, closure) = new_figure((7, 6), 2, 1, sharex=True)
    terms.plot(e["time"], e["kinetic"] - e["kinetic"][0], label="kinetic energy change")
    for name in ENERGY_TERMS:
        if name in e and np.any(e[name] != 0.0):
            terms.plot(e["time"], e[name], label=name.replace("_", " "))
    terms.set_ylabel("J")
    terms.legend(fontsize=8)
    terms.set_title("energy ledger: cumulative terms")
    closure.plot(e["time"], 100.0 * e["closure"], color="k")
    closure.set_xlabel("time, s")
    closure.set_ylabel("closure, % of the energy in play")
    save(fig, out / "energy.png")
    return "![energy](energy.png)"


def _speeds(run: Run, out: Path) -> str:
    g = run.granules
    if not g or not g["time"].size:
        return "no speed figure: granules.csv was not recorded"
    times = np.unique(g["time"])
    fig, ax = new_figure((7, 3.5))
    fastest = float(g["speed"].max(initial=0.0)) or 1.0
    bins = np.linspace(0.0, fastest, 31)
    for t in (times[0], times[-1]):
        ax.hist(g["speed"][g["time"] == t], bins=bins, alpha=0.6, label=f"t = {t:.4g} s")
    ax.set_xlabel("speed, m/s")
    ax.set_ylabel("granules")
    ax.legend()
    save(fig, out / "speeds.png")
    return "![speeds](speeds.png)"


def _impacts(run: Run, out: Path) -> str:
    i = run.impacts
    if not i:
        return "no impact figure: impacts.csv was not recorded"
    if not i["time"].size:
        return "no impact figure: the run had no granule-hammer impact"
    fig, (count, speed) = new_figure((7, 5), 2, 1, sharex=True)
    end = float(run.summary.get("simulated_time") or i["time"].max())
    count.hist(i["time"], bins=np.linspace(0.0, end, 41), color="0.4")
    count.set_ylabel("impacts per bin")
    speed.plot(i["time"], -i["normal_velocity_before"], ".", ms=3)
    speed.set_xlabel("time, s")
    speed.set_ylabel("normal approach speed, m/s")
    save(fig, out / "impacts.png")
    return "![impacts](impacts.png)"


def _paths(run: Run, out: Path) -> str:
    if not run.granules or not run.hammers:
        return "no path figure: granules.csv and hammers.csv are both needed"
    render(run.directory, out / "paths.png", trajectories=True)
    return "![paths](paths.png)"


def _process(run: Run, out: Path) -> list[str]:
    """The process section: the population, each process metric (or why the run cannot give
    it) and the process figure."""
    lines = ["| | | |", "| --- | --- | --- |"]
    for key, count in run.summary["population"].items():
        lines.append(f"| {key.replace('_', ' ')} | {count} | granules |")
    for name in PROCESS_METRICS:
        label, factor = metric_label(name)
        try:
            value = f"{evaluate(run, name) * factor:.4g}"
        except MetricUnavailableError as exc:
            value = f"n/a: {exc}"
        lines.append(f"| {label} | {value} | {METRICS[name].description} |")
    if not run.granules:
        return [*lines, "", "no process figure: granules.csv was not recorded"]
    process_figure(run.directory, out / "process.png")
    return [*lines, "", "![process](process.png)"]


def _closure(energy: dict) -> str:
    """The ledger's closure in words; runs before 2026-11-26 kept no residual."""
    if energy.get("closure") is None:
        return "not kept"
    if "residual" not in energy:
        return f"{energy['closure']:+.3%}"
    return ledger_closure_text(energy)


def write_run_report(directory: Path, out: Path | None = None) -> Path:
    """Write the report of the run in ``directory`` to ``out`` (default ``RUN/report``):
    report.md, its figures and report.html; returns the path of report.md."""
    run = load_run(directory)
    out = out or directory / "report"
    out.mkdir(parents=True, exist_ok=True)
    s = run.summary
    energy = s.get("energy") or {}
    rows = [
        ("status", f"{s.get('status')}" + (f": {s['reason']}" if s.get("reason") else "")),
        ("simulated", f"{s.get('simulated_time', 0):.4g} s in {s.get('steps')} steps of "
                      f"{s.get('dt', 0):.3g} s, {s.get('wall_time', 0):.3g} s of wall time"),
        ("granules at the start, hammers", f"{s.get('granules')}, {s.get('hammers')}"),
        ("granule-hammer impacts", f"{s.get('impacts')}"),
        ("energy ledger closure", _closure(energy)),
    ]  # fmt: skip
    if s.get("speeds"):
        rows.append(("granule speeds at the end", f"{s['speeds']['mean']:.3g} m/s mean, "
                                                  f"{s['speeds']['max']:.3g} m/s max"))  # fmt: skip
    case = path_from(directory, directory / s["case"])  # older runs named it absolute
    lines = [f"# Run {run.name}", "", f"Case: `{case}` (from the run directory)", "", "| | |",
             "| --- | --- |"]  # fmt: skip
    lines += [f"| {k} | {v} |" for k, v in rows]
    for warning in s.get("warnings") or []:
        lines += ["", f"Warning: {warning}"]
    if s.get("population"):
        lines += ["", "## Process", "", *_process(run, out)]
    for title, figure in (("Energy", _energy), ("Speeds", _speeds), ("Impacts", _impacts),
                          ("Paths in the fixed frame", _paths)):  # fmt: skip
        lines += ["", f"## {title}", "", figure(run, out)]
    files = sorted(p.name for p in directory.iterdir() if p.is_file() or p.name == "vtk")
    lines += ["", "## Files", "", ", ".join(f"`{f}`" for f in files)]
    if (directory / "vtk" / "granules.pvd").exists():
        lines += ["", "ParaView: `paraview --state=vtk/paraview_state.py` (or File > Load State)."]
    path = out / "report.md"
    write_markdown_report(path, "\n".join(lines) + "\n")
    return path
