"""The energy ledger's residual from the soft kernel's granule substeps when a hammer strikes a
granule held in the comb: the bundled bee-bread separator cut to one comb cell, no feed or
outlet, struck once in its first 12 ms, at 5 and 1 granule substeps and three steps; then the
whole case's closure at 0.3 s for 5, 2 and 1 substeps (``--full``). With the hammers at their
step-start velocity through the substeps the residual was first order in the machine step;
kicked at every granule step, it is that of one substep (docs/dev/reliability.md).

    python benchmarks/substep_split.py          # ~10 s
    python benchmarks/substep_split.py --full   # ~2 min more
"""

from __future__ import annotations

import argparse
import tempfile
import tomllib
from pathlib import Path

import tomli_w

from perga.case import load_case
from perga.engine.simulation import Simulation
from perga.model.compile import compile_case

CASE = Path("cases/bee-bread-separator.toml")


def residual(case_path: Path, duration: float, overrides: list[str]) -> tuple[float, float]:
    """(the ledger's residual, J; its closure) after ``duration`` s."""
    sim = Simulation(compile_case(load_case(case_path, overrides=overrides)))
    sim.run(duration)
    e = sim.energy()
    change = e.kinetic - e.kinetic_initial + e.elastic - e.elastic_initial
    sources = e.drive_work + e.gravity_work + e.joint_correction + e.inflow - e.outflow
    losses = e.contact_dissipation + e.friction + e.drag
    return sources - change - losses, e.closure


def one_cell(directory: Path) -> Path:
    """The bundled case with one held granule, no feed or outlet, energy recorded only."""
    data = tomllib.loads(CASE.read_text())
    for section in ("feed", "outlet"):
        del data[section]
    data["granules"]["count"] = 1
    data["granules"]["placement"] |= {"rows": 1, "columns": 1}
    shape = data["chamber"]["shape"]
    shape["path"] = str((CASE.parent / shape["path"]).resolve())
    data["output"]["record"] = ["energy"]
    path = directory / "one-cell.toml"
    path.write_text(tomli_w.dumps(data))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--full", action="store_true", help="also the whole case at 0.3 s")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        case = one_cell(Path(tmp))
        print("one comb cell struck once, residual after 12 ms, J:")
        for substeps in (5, 1):
            row = []
            for per_contact in (50, 100, 200):
                sets = [f"contact_model.granule_substeps={substeps}",
                        f"contact_model.steps_per_contact={per_contact}"]  # fmt: skip
                row.append(f"t_c/{per_contact}: {residual(case, 0.012, sets)[0]:+.3e}")
            print(f"  {substeps} substeps: " + ", ".join(row), flush=True)
    if args.full:
        print("the bundled case, closure at 0.3 s:")
        for substeps in (5, 2, 1):
            sets = [f"contact_model.granule_substeps={substeps}"]
            print(f"  {substeps} substeps: {residual(CASE, 0.3, sets)[1]:+.2%}", flush=True)


if __name__ == "__main__":
    main()
