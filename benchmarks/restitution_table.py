"""Issue 16 (must show): the restitution a soft contact gives against the e asked for, at the
default step, for e in {0.05, 0.1, 0.3, 0.6, 0.8, 0.95}: a granule on a wall and on a granule
(the kernel alone, at the step plan's steps for that contact's damping,
``perga.model.plan.steps_for_damping``: ``tests/contact/soft/helpers.impact``, 10 m/s),
and on a 5 g and a 200 g hinged hammer (``cases/soft-single-granule.toml`` through
``Simulation``, one granule step per machine step, the step plan's own step), linear and Hertz
(by duration, 0.1 ms). e below e^-2 ≈ 0.135 is out of reach of a contact that ends at zero
force: those rows take ``end = "overlap"`` and say so.

The turning rotor (``--turning``): the same case's plate hinged (5 g, 200 g) or welded
(200 g) to a rotor turned so that its tip moves at 1, 10 and 40 m/s, e from the impact log
(the contact's own rebound, ``tests/contact/soft/test_impact_log_at_speed.py``), linear and
Hertz. These deviations are the law's own on a turning face (the frame's Coriolis and
centrifugal forces over the contact's duration, docs/dev/validation.md), not the kernel's: the
kernel matches an independent integration of the law on the turning face
(``tests/contact/soft/test_turning_face.py``).

    python benchmarks/restitution_table.py            # ~1 min
    python benchmarks/restitution_table.py --turning  # ~25 min
"""

from __future__ import annotations

import sys
from pathlib import Path

# the tests' helpers (tests.contact.soft.helpers, tests.test_soft_run) are imported from here
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.contact.soft.helpers import impact
from tests.test_soft_run import hammer_restitution

from perga.analytic.contact import FORCE_END_MIN_RESTITUTION, damping_ratio
from perga.model.plan import steps_for_damping

E = (0.05, 0.1, 0.3, 0.6, 0.8, 0.95)


def turning() -> None:
    """The turning rotor's table (module doc)."""
    print("| model | hammer | e | 1 m/s | 10 m/s | 40 m/s |")
    print("| --- | --- | ---: | ---: | ---: | ---: |")
    for model in ("linear", "hertz"):
        for mount, mass in (("welded", 0.2), ("hinged", 0.005), ("hinged", 0.2)):
            for e in E:
                end = "force" if e > FORCE_END_MIN_RESTITUTION else "overlap"
                measured = [
                    hammer_restitution(model, e, end, mass, tip_speed=v, mount=mount)
                    for v in (1.0, 10.0, 40.0)
                ]
                cells = " | ".join(f"{x / e - 1:+.2%}" for x in measured)
                print(f"| {model} | {mount} {mass * 1e3:g} g | {e} | {cells} |", flush=True)


def main() -> None:
    if "--turning" in sys.argv[1:]:
        turning()
        return
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
            hammers = [hammer_restitution(model, e, end, m) for m in (0.005, 0.2)]
            cells = " | ".join(f"{(x / e - 1):+.2%}" for x in kernel + hammers)
            print(f"| {model} | {e} | {end} | {cells} |", flush=True)


if __name__ == "__main__":
    main()
