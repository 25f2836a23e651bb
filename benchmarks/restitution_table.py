"""Issue 16 (must show): the restitution a soft contact gives against the e asked for, at the
default step, for e in {0.05, 0.1, 0.3, 0.6, 0.8, 0.95}: a granule on a wall and on a granule
(the kernel alone, at the step plan's steps for that contact's damping,
``perga.case.timestep.steps_for_damping``: ``tests/contact/soft/helpers.impact``, 10 m/s),
and on a 5 g and a 200 g hinged hammer (``cases/soft-single-granule.toml`` through
``Simulation``, one granule step per machine step, the step plan's own step), linear and Hertz
(by duration, 0.1 ms). e below e^-2 ≈ 0.135 is out of reach of a contact that ends at zero
force: those rows take ``end = "overlap"`` and say so.

    python benchmarks/restitution_table.py            # ~1 min
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.contact.soft.helpers

from tests.contact.soft.helpers import impact

from perga.analytic.contact import FORCE_END_MIN_RESTITUTION, damping_ratio
from perga.case import load_case
from perga.case.timestep import steps_for_damping
from perga.engine.simulation import Simulation
from perga.model.from_case import scene_spec

E = (0.05, 0.1, 0.3, 0.6, 0.8, 0.95)
CASE = Path(__file__).resolve().parents[1] / "cases" / "soft-single-granule.toml"


def on_hammer(model: str, e: float, end: str, mass: float) -> float:
    """e of the first granule-hammer impact (relative to the hammer's material point)."""
    sets = [f"hammers.mass={mass}", f"contacts[0].restitution={e}", f'contact_model.end="{end}"',
            f'contact_model.kind="{model}"', "contact_model.granule_substeps=1"]  # fmt: skip
    sim = Simulation(scene_spec(load_case(CASE, overrides=sets)), track_energy=False)
    with sim.contacts.running():
        while not sim.impacts and sim.time < 0.05:
            sim.step()
    first = sim.impacts[0]
    return -first.normal_velocity_after / first.normal_velocity_before


def main() -> None:
    print("| model | e | end | wall | granule | 5 g hammer | 200 g hammer |")
    print("| --- | ---: | --- | ---: | ---: | ---: | ---: |")
    for model in ("linear", "hertz"):
        for e in E:
            end = "force" if e > FORCE_END_MIN_RESTITUTION else "overlap"
            k = 1e6 if model == "linear" else 1e9  # N/m, N/m^1.5: helpers' defaults
            fraction = 1.0 / steps_for_damping(damping_ratio(e, end), 50.0)
            kernel = [
                impact(model, e, 10.0, kind, end=end, k_n=k, dt_fraction=fraction).e
                for kind in ("wall", "pair")
            ]
            hammers = [on_hammer(model, e, end, m) for m in (0.005, 0.2)]
            cells = " | ".join(f"{(x / e - 1):+.2%}" for x in kernel + hammers)
            print(f"| {model} | {e} | {end} | {cells} |", flush=True)


if __name__ == "__main__":
    main()
