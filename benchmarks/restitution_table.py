"""Issue 16 (must show): the restitution a soft contact gives against the e asked for, at the
default step, for e in {0.05, 0.1, 0.3, 0.6, 0.8, 0.95}: a granule on a wall and on a granule
(the kernel alone, at the step plan's steps for that contact's damping,
``perga.model.plan.steps_for_damping``: ``tests/contact/soft/helpers.impact``, 10 m/s),
and on a 5 g and a 200 g hinged hammer (``cases/soft-single-granule.toml`` through
``Simulation``, one granule step per machine step, the step plan's own step), linear and Hertz
(by duration, 0.1 ms). e below e^-2 ≈ 0.135 is out of reach of a contact that ends at zero
force: those rows take ``end = "overlap"`` and say so.

    python benchmarks/restitution_table.py            # ~1 min
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
            hammers = [hammer_restitution(model, e, end, m) for m in (0.005, 0.2)]
            cells = " | ".join(f"{(x / e - 1):+.2%}" for x in kernel + hammers)
            print(f"| {model} | {e} | {end} | {cells} |", flush=True)


if __name__ == "__main__":
    main()
