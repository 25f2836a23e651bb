"""Issue 18, item 4: the decay rate of a sticking contact's slip against the closed form ζω
(ζ = √3 ζ_t, ω² = 3k_t/m for a disc on a floor), at several steps and with ζ_t = 0, through
``tests/cases/closed-form/sticking-oscillation.toml`` (docs/dev/validation.md, "Tangential damping
of a sticking contact").

    python benchmarks/sticking_oscillation.py            # t_c/50, 100, 200, 400; ~1 min
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from perga.case import load_case
from perga.model.compile import compile_case

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.test_closed_form_cases import _slip_decay

CASE = Path(__file__).resolve().parents[1] / "tests" / "cases" / "closed-form"
CASE = CASE / "sticking-oscillation.toml"


def decay_rate(sets: list[str]) -> float:
    """The slip's decay rate over 6 ms with ``sets``, 1/s (the test's measure)."""
    return _slip_decay(load_case(CASE, overrides=sets))[0]


def main() -> None:
    case = load_case(CASE)
    spec = compile_case(case)
    r, m = case.granules.radius, case.granules.mass
    k_n = spec.contact("beebread", "steel").stiffness
    delta = m * float(np.hypot(*spec.gravity)) / k_n
    start = [
        f"granules.placement.positions=[[0.0, {-0.2 + r - delta!r}]]",
        f"granules.placement.overlap={1.01 * delta!r}",
    ]
    cm = case.contact_model
    exact = math.sqrt(3) * cm.tangential_damping * math.sqrt(3 * cm.tangential_ratio * k_n / m)
    print(f"closed form ζω = {exact:.2f} /s")
    for steps in (50, 100, 200, 400):
        at = [*start, f"contact_model.steps_per_contact={steps}"]
        rate = decay_rate(at)
        alone = decay_rate([*at, "contact_model.tangential_damping=0.0"])
        print(f"t_c/{steps}: rate {rate:.2f} /s ({rate / exact - 1:+.2%}), with ζ_t = 0 "
              f"{alone:.2f} /s, difference {(rate - alone) / exact - 1:+.3%}")  # fmt: skip


if __name__ == "__main__":
    main()
